// OpenVDB density grids: the dense grid the reader makes, looked up through the medium's own
// trilinear interpolation, against OpenVDB's trilinear sampler (tools::BoxSampler) on the file's
// grid; the same grid through Mitsuba's gridvolume and pbrt-v4's nanovdb forms; clear errors.
#include "common/scene/loaders/vdb_reader.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <string>

#include "common/sampling/rng.h"
#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/loaders/pbrt_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"
#include "common/scene/medium.h"

namespace farm {
namespace {

// A grid of 0.1-unit voxels moved to (1, 2, 3), with a 4 x 3 x 5 block of uneven densities.
openvdb::FloatGrid::Ptr smokeGrid(const std::string& name = "density") {
  openvdb::initialize();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
  grid->setName(name);
  openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(0.1);
  transform->postRotate(0.3, openvdb::math::Y_AXIS);
  transform->postTranslate(openvdb::Vec3d(1, 2, 3));
  grid->setTransform(transform);
  openvdb::FloatGrid::Accessor access = grid->getAccessor();
  Rng rng(4, 4);
  for (int x = -2; x < 2; ++x)
    for (int y = 5; y < 8; ++y)
      for (int z = 0; z < 5; ++z) access.setValue(openvdb::Coord(x, y, z), 3 * rng.nextFloat());
  return grid;
}

std::string writeVdb(const TempDir& dir, const std::string& name, openvdb::GridPtrVec grids) {
  const std::string path = (dir.path() / name).string();
  openvdb::io::File(path).write(grids);
  return path;
}

// The medium's density against OpenVDB's own trilinear lookup, at world points in and around
// the active block (after moving the grid by `mediumToWorld`).
void expectSameDensity(const MediumDescription& desc, const openvdb::FloatGrid& grid,
                       const Matrix4& mediumToWorld = Matrix4::identity()) {
  const Medium medium(desc);
  Rng rng(9, 9);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    const openvdb::Vec3d index(-3.5 + 6 * rng.nextDouble(), 3.5 + 6 * rng.nextDouble(),
                               -1.5 + 7 * rng.nextDouble());
    const openvdb::Vec3d local = grid.transform().indexToWorld(index);
    const Vec3f world =
        mediumToWorld.applyPoint(Vec3f(float(local.x()), float(local.y()), float(local.z())));
    const float expected = openvdb::tools::BoxSampler::sample(grid.getConstAccessor(), index);
    inside += expected > 0;
    ASSERT_NEAR(medium.density(world), expected, 2e-4f) << "index " << index;
  }
  EXPECT_GT(inside, 500);
}

TEST(VdbReader, DenseGridInterpolatesAsOpenVdbDoes) {
  TempDir dir;
  openvdb::FloatGrid::Ptr grid = smokeGrid();
  const std::string path = writeVdb(dir, "smoke.vdb", {grid});
  MediumDescription desc;
  desc.sigmaS = Spectrum(1.0f);
  std::string problem;
  ASSERT_TRUE(readVdbDensity(path, "density", &desc, &problem)) << problem;
  EXPECT_EQ(mediumProblem(desc), "");
  EXPECT_EQ(desc.nx, 6);  // the 4 x 3 x 5 block and a voxel of zeros around it
  EXPECT_EQ(desc.ny, 5);
  EXPECT_EQ(desc.nz, 7);
  expectSameDensity(desc, *grid);
  // No name: the first float grid.
  MediumDescription first;
  ASSERT_TRUE(readVdbDensity(path, "", &first, &problem)) << problem;
  EXPECT_EQ(first.density, desc.density);
}

TEST(VdbReader, MitsubaAndPbrtFormsReadIt) {
  TempDir dir;
  openvdb::FloatGrid::Ptr grid = smokeGrid();
  writeVdb(dir, "smoke.vdb", {grid});
  const SceneDescription mitsuba = loadMitsubaScene(dir.write("m.xml", R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <medium type="heterogeneous" id="smoke">
    <volume name="density" type="gridvolume">
      <string name="filename" value="smoke.vdb"/>
      <transform name="toWorld"><translate x="10"/></transform>
    </volume>
  </medium>
  <shape type="cube"><ref name="interior" id="smoke"/></shape>
</scene>
)"));
  ASSERT_EQ(mitsuba.media.size(), 1u);
  expectSameDensity(mitsuba.media[0], *grid, Matrix4::translate(Vec3f(10, 0, 0)));

  const SceneDescription pbrt = loadPbrtScene(dir.write("p.pbrt", R"(Camera "perspective"
WorldBegin
AttributeBegin
  Translate 0 -5 0
  MakeNamedMedium "smoke" "string type" "nanovdb" "string filename" "smoke.vdb"
      "rgb sigma_a" [1 1 1] "rgb sigma_s" [2 2 2]
AttributeEnd
MediumInterface "smoke" ""
Material "interface"
Shape "sphere"
)"));
  ASSERT_EQ(pbrt.media.size(), 1u);
  expectSameDensity(pbrt.media[0], *grid, Matrix4::translate(Vec3f(0, -5, 0)));
}

TEST(VdbReader, BadFilesAreClearErrors) {
  TempDir dir;
  openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
  velocity->setName("velocity");
  velocity->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 0, 0));
  writeVdb(dir, "velocity.vdb", {velocity});
  writeVdb(dir, "smoke.vdb", {smokeGrid("smoke")});
  dir.write("garbage.vdb", "not a volume at all, just some words in a file");
  MediumDescription desc;
  std::string problem;
  EXPECT_FALSE(readVdbDensity(dir.path() / "velocity.vdb", "velocity", &desc, &problem));
  EXPECT_NE(problem.find("not float"), std::string::npos) << problem;
  EXPECT_FALSE(readVdbDensity(dir.path() / "velocity.vdb", "", &desc, &problem));
  EXPECT_NE(problem.find("no float grid"), std::string::npos) << problem;
  EXPECT_FALSE(readVdbDensity(dir.path() / "smoke.vdb", "density", &desc, &problem));
  EXPECT_NE(problem.find("no grid named 'density'"), std::string::npos) << problem;
  EXPECT_FALSE(readVdbDensity(dir.path() / "garbage.vdb", "", &desc, &problem));
  EXPECT_NE(problem.find("OpenVDB"), std::string::npos) << problem;

  const std::string header = "Camera \"perspective\"\nWorldBegin\n";
  expectLoadError(
      dir.write("a.pbrt", header + "MakeNamedMedium \"s\" \"string type\" \"nanovdb\" "
                                   "\"string filename\" \"smoke.nvdb\" \"rgb sigma_a\" [1 "
                                   "1 1] \"rgb sigma_s\" [1 1 1]\n"),
      "NanoVDB files are not read", 3);
  expectLoadError(
      dir.write("b.pbrt", header + "MakeNamedMedium \"s\" \"string type\" \"nanovdb\" "
                                   "\"string filename\" \"smoke.vdb\" \"rgb sigma_a\" [1 1 "
                                   "1] \"rgb sigma_s\" [1 1 1]\n"),
      "no grid named 'density'", 3);
}

}  // namespace
}  // namespace farm
