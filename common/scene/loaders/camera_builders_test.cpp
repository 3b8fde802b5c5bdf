#include "common/scene/loaders/camera_builders.h"

#include <gtest/gtest.h>

#include <string>

#include "common/scene/loaders/scene_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

// The table in camera_builders.h read off the loaders: Mitsuba's gaussian of stddev 0.25 (cut off
// at 4 stddev) is pbrt-v4's of sigma 0.25 and radius 1, and pbrt-v3's of alpha 8 and width 1
// (none of them the description's default).
TEST(CameraBuilders, TheSameGaussianFilterInEitherFormatIsTheSameFilter) {
  TempDir dir("camera_builders_test");
  const SceneDescription m = loadSceneDescription(dir.write(
      "m.xml",
      "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n<sensor type=\"perspective\">"
      "<film type=\"hdrfilm\"><rfilter type=\"gaussian\"><float name=\"stddev\" value=\"0.25\"/>"
      "</rfilter></film></sensor>\n</scene>\n"));
  const std::string camera = "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\n";
  const std::string world = "WorldBegin\nShape \"sphere\" \"float radius\" [1]\n";
  const SceneDescription v4 = loadSceneDescription(dir.write(
      "v4.pbrt", camera +
                     "PixelFilter \"gaussian\" \"float xradius\" [1] \"float yradius\" [1] "
                     "\"float sigma\" [0.25]\n" +
                     world));
  const SceneDescription v3 = loadSceneDescription(
      dir.write("v3.pbrt", camera +
                               "PixelFilter \"gaussian\" \"float xwidth\" [1] \"float ywidth\" [1] "
                               "\"float alpha\" [8]\n" +
                               world));
  for (const SceneDescription* p : {&v4, &v3}) {
    EXPECT_EQ(p->camera.filter, FilterType::Gaussian);
    EXPECT_EQ(p->camera.filter, m.camera.filter);
    EXPECT_EQ(p->camera.filterRadius, m.camera.filterRadius);
    EXPECT_EQ(p->camera.filterAlpha, m.camera.filterAlpha);
  }
  EXPECT_EQ(m.camera.filterRadius, 1.0f);
  EXPECT_EQ(m.camera.filterAlpha, 8.0f);
}

std::string mitsubaFilmOfWidth(long long width) {
  return "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n<sensor type=\"perspective\">"
         "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
         std::to_string(width) +
         "\"/><integer name=\"height\" value=\"1\"/></film></sensor>\n</scene>\n";
}

std::string pbrtFilmOfWidth(long long width) {
  return "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer "
         "xresolution\" [" +
         std::to_string(width) + "] \"integer yresolution\" [1]\nWorldBegin\nShape \"sphere\"\n";
}

TEST(CameraBuilders, BothFormatsTakeAFilmUpToTheSameSize) {
  TempDir dir("camera_builders_test");
  EXPECT_EQ(loadError(dir.write("at.xml", mitsubaFilmOfWidth(kMaxFilmSide))), "");
  EXPECT_EQ(loadError(dir.write("at.pbrt", pbrtFilmOfWidth(kMaxFilmSide))), "");
  EXPECT_NE(loadError(dir.write("wide.xml", mitsubaFilmOfWidth(kMaxFilmSide + 1)))
                .find("film width 65537 is not in [1, 65536]"),
            std::string::npos);
  EXPECT_NE(loadError(dir.write("wide.pbrt", pbrtFilmOfWidth(kMaxFilmSide + 1)))
                .find("film resolution 65537x1 is outside 1..65536"),
            std::string::npos);
}

}  // namespace
}  // namespace farm
