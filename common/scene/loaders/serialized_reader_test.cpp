// Mitsuba serialized meshes: files written here, byte by byte as the format's documentation
// describes them, read back exactly; through the Mitsuba loader; and every malformed file refused
// with its reason.
#include "common/scene/loaders/serialized_reader.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

template <typename T>
void put(std::string* out, T v) {
  for (size_t i = 0; i < sizeof(T); ++i) out->push_back(char((uint64_t(v) >> (8 * i)) & 0xff));
}
void putReal(std::string* out, double v, bool doubles) {
  if (doubles) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    put(out, bits);
  } else {
    const float f = float(v);
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    put(out, bits);
  }
}

struct MeshToWrite {
  std::vector<double> positions, normals, uvs;  // flat
  std::vector<uint32_t> indices;
  bool doubles = false, faceNormals = false, colors = false;
  uint64_t claimedVertices = 0;  // written in place of the true count when not 0
  std::string trailing;          // bytes after the triangles
  uint64_t vertexCount() const { return positions.size() / 3; }
};

// The zlib-compressed part of one mesh.
std::string meshStream(const MeshToWrite& m, int version) {
  std::string raw;
  uint32_t flags = m.doubles ? 0x2000 : 0x1000;
  if (!m.normals.empty()) flags |= 0x0001;
  if (!m.uvs.empty()) flags |= 0x0002;
  if (m.colors) flags |= 0x0008;
  if (m.faceNormals) flags |= 0x0010;
  put(&raw, flags);
  if (version == 4) raw += std::string("mesh name") + '\0';
  put(&raw, m.claimedVertices ? m.claimedVertices : m.vertexCount());
  put(&raw, uint64_t(m.indices.size() / 3));
  for (double v : m.positions) putReal(&raw, v, m.doubles);
  for (double v : m.normals) putReal(&raw, v, m.doubles);
  for (double v : m.uvs) putReal(&raw, v, m.doubles);
  if (m.colors)
    for (size_t i = 0; i < m.positions.size(); ++i) putReal(&raw, 0.5, m.doubles);
  for (uint32_t i : m.indices) put(&raw, i);
  raw += m.trailing;
  uLongf size = compressBound(uLong(raw.size()));
  std::string z(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(z.data()), &size,
                      reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 6),
            Z_OK);
  z.resize(size);
  return z;
}

std::string serializedFile(const std::vector<MeshToWrite>& meshes, int version = 4) {
  std::string file;
  std::vector<uint64_t> offsets;
  for (const MeshToWrite& m : meshes) {
    offsets.push_back(file.size());
    put(&file, uint16_t(0x041C));
    put(&file, uint16_t(version));
    file += meshStream(m, version);
  }
  for (uint64_t o : offsets) version == 4 ? put(&file, o) : put(&file, uint32_t(o));
  put(&file, uint32_t(meshes.size()));
  return file;
}

MeshToWrite quad() {
  MeshToWrite m;
  m.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
  m.indices = {0, 1, 2, 2, 3, 0};
  return m;
}

MeshToWrite triangle() {
  MeshToWrite m;
  m.positions = {0, 0, 0.1, 2, 0, 0.1, 0, 3, 0.1};
  m.indices = {0, 1, 2};
  m.doubles = true;
  m.faceNormals = true;
  m.colors = true;
  return m;
}

void expectMesh(const SerializedMesh& got, const MeshToWrite& want) {
  ASSERT_EQ(got.positions.size(), want.vertexCount());
  for (size_t i = 0; i < got.positions.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_FLOAT_EQ(got.positions[i][k], float(want.positions[3 * i + k]));
  ASSERT_EQ(got.normals.size(), want.normals.size() / 3);
  for (size_t i = 0; i < got.normals.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(got.normals[i][k], float(want.normals[3 * i + k]));
  ASSERT_EQ(got.uvs.size(), want.uvs.size() / 2);
  for (size_t i = 0; i < got.uvs.size(); ++i) {
    EXPECT_FLOAT_EQ(got.uvs[i].x, float(want.uvs[2 * i]));
    EXPECT_FLOAT_EQ(got.uvs[i].y, float(want.uvs[2 * i + 1]));
  }
  EXPECT_EQ(got.indices, want.indices);
  EXPECT_EQ(got.faceNormals, want.faceNormals);
}

constexpr size_t kBudget = size_t(1) << 28;

TEST(SerializedMesh, ReadsEachMeshOfVersionsThreeAndFour) {
  for (int version : {3, 4}) {
    const std::string file = serializedFile({quad(), triangle(), quad()}, version);
    expectMesh(parseSerialized(file, 0, kBudget), quad());
    expectMesh(parseSerialized(file, 1, kBudget), triangle());
    expectMesh(parseSerialized(file, 2, kBudget), quad());
  }
}

TEST(SerializedMesh, TheMitsubaLoaderPlacesItAndFlipsItsV) {
  TempDir dir;
  dir.write("meshes/both.serialized", serializedFile({triangle(), quad()}));
  SceneDescription s = loadMitsubaScene(dir.write(
      "s.xml",
      "<scene version=\"0.6.0\">\n"
      "<shape type=\"serialized\"><string name=\"filename\" value=\"meshes/both.serialized\"/>"
      "<integer name=\"shapeIndex\" value=\"1\"/>"
      "<transform name=\"toWorld\"><translate z=\"5\"/></transform></shape>\n"
      "<shape type=\"serialized\"><string name=\"filename\" value=\"meshes/both.serialized\"/>"
      "</shape>\n</scene>\n"));
  ASSERT_EQ(s.shapes.size(), 2u);
  const ShapeDescription& q = s.shapes[0];
  ASSERT_EQ(q.positions.size(), 4u);
  EXPECT_FLOAT_EQ(q.positions[2].z, 5.0f);
  ASSERT_EQ(q.uvs.size(), 4u);
  // Mitsuba reads row v from the image's top; the description's t runs from its bottom.
  EXPECT_FLOAT_EQ(q.uvs[0].y, 1.0f);
  EXPECT_FLOAT_EQ(q.uvs[2].y, 0.0f);
  EXPECT_FALSE(q.faceNormals);
  EXPECT_TRUE(s.shapes[1].faceNormals);  // the file's flag
  EXPECT_EQ(s.shapes[1].indices.size(), 3u);
}

TEST(SerializedMesh, MalformedFilesAreRefusedWithTheirReason) {
  const std::string good = serializedFile({quad()});
  struct Bad {
    std::string bytes;
    int index;
    std::string message;
  };
  std::vector<Bad> cases;
  cases.push_back({"PK\x03\x04 not a mesh", 0, "no 0x041C header"});
  cases.push_back({std::string("\x04\x1c\x04\x00", 4) + good.substr(4), 0, "old Mitsuba"});
  std::string v5 = good;
  v5[2] = 5;
  cases.push_back({v5, 0, "version 5 is not supported"});
  cases.push_back({good, 1, "shapeIndex 1 is beyond the file's 1 meshes"});
  cases.push_back({good.substr(0, 30), 0, "the file ends inside the mesh's"});
  std::string header = good;  // the zlib stream's own header
  header[4] = char(~header[4]);
  cases.push_back({header, 0, "corrupt compressed data in the mesh's flags"});
  std::string checksum = good;  // the stream's adler32, before the 12-byte dictionary
  checksum[good.size() - 13] = char(~checksum[good.size() - 13]);
  cases.push_back({checksum, 0, "(incorrect data check)"});
  MeshToWrite longer = quad();  // data beyond what the counts call for
  longer.trailing = "0123";
  cases.push_back({serializedFile({longer}), 0, "more data than its counts"});
  MeshToWrite outOfRange = quad();
  outOfRange.indices[4] = 7;
  cases.push_back({serializedFile({outOfRange}), 0, "triangle 1 names vertex 7 of 4"});
  MeshToWrite nan = quad();
  nan.positions[4] = std::numeric_limits<double>::quiet_NaN();
  cases.push_back({serializedFile({nan}), 0, "non-finite"});
  MeshToWrite huge = triangle();
  huge.doubles = false;
  huge.positions.assign(3 * 1000, 0.0);  // counts that claim more than the budget below
  cases.push_back({serializedFile({huge}), 0, "exceed the scene's budget"});
  MeshToWrite empty = quad();
  empty.indices.clear();
  cases.push_back({serializedFile({empty}), 0, "no vertices or no triangles"});
  MeshToWrite lying = quad();  // counts larger than the data: the stream ends early
  lying.claimedVertices = 100;
  cases.push_back({serializedFile({lying}), 0, "the mesh's data ends inside its positions"});
  for (const Bad& c : cases) {
    const size_t budget = c.message == "exceed the scene's budget" ? 500 : kBudget;
    try {
      parseSerialized(c.bytes, c.index, budget);
      ADD_FAILURE() << "accepted a file that should fail with: " << c.message;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << e.what() << "\n  wanted: " << c.message;
    }
  }
}

TEST(SerializedMesh, LoaderErrorsNameFileAndLine) {
  TempDir dir;
  dir.write("junk.serialized", "junk");
  dir.write("one.serialized", serializedFile({quad()}));
  struct Bad {
    std::string shape, message;
  };
  const Bad cases[] = {
      {"<string name=\"filename\" value=\"junk.serialized\"/>",
       "cannot read serialized mesh 'junk.serialized': not a Mitsuba serialized mesh"},
      {"<string name=\"filename\" value=\"missing.serialized\"/>", "not found"},
      {"<string name=\"filename\" value=\"one.serialized\"/><integer name=\"shapeIndex\" "
       "value=\"-1\"/>",
       "shapeIndex must be >= 0"},
      {"<string name=\"filename\" value=\"one.serialized\"/><integer name=\"shapeIndex\" "
       "value=\"3\"/>",
       "beyond the file's 1 meshes"},
      {"<string name=\"filename\" value=\"one.serialized\"/><float name=\"maxSmoothAngle\" "
       "value=\"30\"/>",
       "maxSmoothAngle"},
  };
  for (const Bad& c : cases) {
    const std::string path =
        dir.write("s.xml", "<scene version=\"0.6.0\">\n\n<shape type=\"serialized\">" + c.shape +
                               "</shape>\n</scene>\n");
    expectLoadError(path, c.message, 3);
  }
}

}  // namespace
}  // namespace farm
