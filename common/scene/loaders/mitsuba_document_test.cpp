// Mitsuba's XML apart from the scene it describes: lines, ids and values (MitsubaDocument) and
// an object's named parameters (MitsubaProperties), each error naming its line, without any scene
// built. The loader's own tests (mitsuba_loader_test.cpp) cover what the elements mean.
#include "common/scene/loaders/mitsuba_document.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "common/scene/loaders/mitsuba_properties.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

std::string scene(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n" + body + "</scene>\n";
}

// The error `run` throws on the document of `text`: its line and problem.
SceneLoadError errorOf(const std::string& text,
                       const std::function<void(MitsubaDocument&)>& run = nullptr) {
  TempDir dir("mitsuba_document_test");
  return thrownLoadError(
      [&] {
        MitsubaDocument document(dir.write("scene.xml", text));
        if (run) run(document);
      },
      "no error for: " + text);
}

// The first element child of the root.
pugi::xml_node first(const MitsubaDocument& d) {
  return d.root().first_child();
}

TEST(MitsubaDocument, RefusesWhatIsNotAMitsubaZeroScene) {
  EXPECT_EQ(errorOf("<scene version=\"0.5.0\">\n<bsdf>\n").line(), 3);
  EXPECT_NE(errorOf("<scene version=\"0.5.0\">\n<bsdf>\n").problem().find("malformed XML"),
            std::string::npos);
  EXPECT_NE(errorOf("<scenes version=\"0.5.0\"/>").problem().find("must be <scene>"),
            std::string::npos);
  EXPECT_NE(errorOf("<scene version=\"3.0.0\"/>").problem().find("not Mitsuba 0.x"),
            std::string::npos);
  EXPECT_NE(errorOf("<scene version=\"0.x\"/>").problem().find("invalid scene version"),
            std::string::npos);
  std::string deep;
  for (int i = 0; i < 80; ++i) deep += "<shape>";
  for (int i = 0; i < 80; ++i) deep += "</shape>";
  EXPECT_NE(errorOf(scene(deep)).problem().find("nested too deeply"), std::string::npos);
}

TEST(MitsubaDocument, TellsReferencesApartByWhatIsWrongWithThem) {
  const std::string text = scene(
      "<ref id=\"later\"/>\n"                    // line 3: before its declaration
      "<bsdf type=\"diffuse\" id=\"later\"/>\n"  // line 4
      "<texture type=\"bitmap\" id=\"tex\"/>\n"  // line 5
      "<ref id=\"nobody\"/>\n"                   // line 6
      "<ref id=\"tex\"/>\n");                    // line 7
  // In document order, as the loader goes: objects registered as they come, the `child`-th
  // element resolved as a <ref> to a `kind`.
  auto refError = [&](int child, const char* kind) {
    return errorOf(text, [&](MitsubaDocument& d) {
      int i = 0;
      for (pugi::xml_node n : d.root().children()) {
        if (std::string(n.name()) == "bsdf") d.registerId(n, "bsdf", 0);
        if (std::string(n.name()) == "texture") d.registerId(n, "texture", 0);
        if (i++ == child) d.resolveRef(n, kind);
      }
    });
  };
  SceneLoadError forward = refError(0, "bsdf");
  EXPECT_EQ(forward.line(), 3);
  EXPECT_NE(forward.problem().find("before its declaration at line 4"), std::string::npos);
  EXPECT_NE(refError(3, "bsdf").problem().find("unknown id 'nobody'"), std::string::npos);
  SceneLoadError kind = refError(4, "bsdf");
  EXPECT_EQ(kind.line(), 7);
  EXPECT_NE(kind.problem().find("names a <texture> (line 5), but a <bsdf> is needed"),
            std::string::npos);
  SceneLoadError twice = errorOf(text, [](MitsubaDocument& d) {
    for (pugi::xml_node n : d.root().children())
      if (std::string(n.name()) == "bsdf") d.registerId(n, "bsdf", 0), d.registerId(n, "bsdf", 1);
  });
  EXPECT_NE(twice.problem().find("duplicate id 'later' (first declared at line 4)"),
            std::string::npos);
}

TEST(MitsubaDocument, ReadsValuesAndNamesTheLineOfABadOne) {
  TempDir dir("mitsuba_document_test");
  MitsubaDocument d(
      dir.write("scene.xml", scene("<transform name=\"t\"><translate x=\"1\" y=\"2\"/>"
                                   "<scale value=\"2\"/></transform>\n"
                                   "<srgb name=\"c\" value=\"#ff0000\"/>\n"
                                   "<point name=\"p\" value=\"1, 2 3\"/>\n")));
  pugi::xml_node t = first(d), c = t.next_sibling(), p = c.next_sibling();
  const Matrix4 m = d.transformOf(t);
  const Vec3f moved = m.applyPoint(Vec3f(0, 0, 0));
  EXPECT_EQ(moved.x, 2.0f);  // translated, then scaled
  EXPECT_EQ(moved.y, 4.0f);
  EXPECT_EQ(d.spectrumOf(c).x, 1.0f);
  EXPECT_EQ(d.spectrumOf(c).y, 0.0f);
  EXPECT_EQ(d.xyzOf(p, 0).z, 3.0f);
  EXPECT_EQ(d.origin(p), "scene.xml:5");

  const std::string bad = scene("\n<float name=\"f\" value=\"nan\"/>\n");
  SceneLoadError nan = errorOf(bad, [](MitsubaDocument& doc) {
    doc.number(first(doc), doc.requireValue(first(doc)), "parameter 'f'");
  });
  EXPECT_EQ(nan.line(), 4);
  EXPECT_NE(nan.problem().find("'nan' is not a finite number"), std::string::npos);
  SceneLoadError huge =
      errorOf(scene("<float name=\"f\" value=\"1e300\"/>\n"),
              [](MitsubaDocument& doc) { doc.number(first(doc), "1e300", "parameter 'f'"); });
  EXPECT_NE(huge.problem().find("out of range"), std::string::npos);
  SceneLoadError singular =
      errorOf(scene("<transform name=\"t\"><scale value=\"0\"/></transform>\n"),
              [](MitsubaDocument& doc) { doc.transformOf(first(doc)); });
  EXPECT_NE(singular.problem().find("singular"), std::string::npos);
}

TEST(MitsubaProperties, ReadsByNameAndTypeAndRefusesWhatNobodyRead) {
  TempDir dir("mitsuba_document_test");
  MitsubaDocument d(dir.write("scene.xml", scene("<bsdf type=\"dielectric\">\n"
                                                 "  <string name=\"intIOR\" value=\"Water\"/>\n"
                                                 "  <boolean name=\"flag\" value=\"TRUE\"/>\n"
                                                 "  <rgb name=\"color\" value=\"0.5\"/>\n"
                                                 "  <float name=\"extra\" value=\"1\"/>\n"
                                                 "  <bsdf type=\"diffuse\"/>\n"
                                                 "</bsdf>\n")));
  std::vector<pugi::xml_node> nested;
  MitsubaProperties props(d, first(d), &nested);
  ASSERT_EQ(nested.size(), 1u);
  EXPECT_TRUE(props.has("extra"));
  EXPECT_DOUBLE_EQ(props.getIor("intIOR", 1.5), 1.333);
  EXPECT_DOUBLE_EQ(props.getIor("extIOR", 1.0), 1.0);  // absent: the default
  EXPECT_TRUE(props.getBoolean("flag", false));
  EXPECT_EQ(props.getSpectrum("color", Spectrum(0.0f)).z, 0.5f);
  const SceneLoadError unread =
      thrownLoadError([&] { props.rejectUnused("bsdf 'dielectric'"); }, "'extra' was never read");
  EXPECT_EQ(unread.line(), 7);
  EXPECT_EQ(unread.problem(), "unsupported parameter 'extra' for bsdf 'dielectric'");
  // Nested objects where none may be; a parameter twice; of the wrong type.
  SceneLoadError nestedError =
      errorOf(scene("<emitter>\n<bsdf/>\n</emitter>\n"),
              [](MitsubaDocument& doc) { MitsubaProperties p(doc, first(doc), nullptr); });
  EXPECT_EQ(nestedError.line(), 4);
  SceneLoadError twice = errorOf(
      scene("<bsdf>\n<float name=\"a\" value=\"1\"/>\n<float name=\"a\" value=\"2\"/>\n</bsdf>\n"),
      [](MitsubaDocument& doc) { MitsubaProperties p(doc, first(doc), nullptr); });
  EXPECT_EQ(twice.line(), 5);
  EXPECT_NE(twice.problem().find("given twice"), std::string::npos);
  SceneLoadError type = errorOf(scene("<bsdf>\n<rgb name=\"flag\" value=\"1\"/>\n</bsdf>\n"),
                                [](MitsubaDocument& doc) {
                                  MitsubaProperties p(doc, first(doc), nullptr);
                                  p.getBoolean("flag", false);
                                });
  EXPECT_NE(type.problem().find("parameter 'flag' must be <boolean>, not <rgb>"),
            std::string::npos);
  SceneLoadError name = errorOf(scene("<bsdf>\n<string name=\"intIOR\" value=\"unobtainium\"/>\n"
                                      "</bsdf>\n"),
                                [](MitsubaDocument& doc) {
                                  MitsubaProperties p(doc, first(doc), nullptr);
                                  p.getIor("intIOR", 1.5);
                                });
  EXPECT_NE(name.problem().find("unknown material 'unobtainium'"), std::string::npos);
}

}  // namespace
}  // namespace farm
