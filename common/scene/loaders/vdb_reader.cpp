#include "common/scene/loaders/vdb_reader.h"

#include <openvdb/openvdb.h>

#include <cmath>
#include <mutex>

namespace farm {

namespace {

constexpr long long kMaxDenseValues = 1ll << 27;

}  // namespace

bool readVdbDensity(const std::filesystem::path& path, const std::string& gridName,
                    MediumDescription* medium, std::string* problem) {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
  try {
    openvdb::io::File file(path.string());
    file.open(false);  // read the whole file now: no delayed loading from a file we may lose
    openvdb::GridBase::Ptr base;
    if (gridName.empty()) {
      for (auto it = file.beginName(); it != file.endName() && !base; ++it) {
        openvdb::GridBase::Ptr candidate = file.readGrid(it.gridName());
        if (candidate->isType<openvdb::FloatGrid>()) base = candidate;
      }
      if (!base) {
        *problem = "the file holds no float grid";
        return false;
      }
    } else {
      if (!file.hasGrid(gridName)) {
        *problem = "the file has no grid named '" + gridName + "'";
        return false;
      }
      base = file.readGrid(gridName);
    }
    file.close();
    openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid) {
      *problem = "grid '" + base->getName() + "' holds " + base->valueType() + ", not float";
      return false;
    }
    if (!grid->transform().isLinear()) {
      *problem = "grid '" + grid->getName() + "' has a frustum (non-affine) transform";
      return false;
    }
    const openvdb::CoordBBox active = grid->evalActiveVoxelBoundingBox();
    if (active.empty()) {
      *problem = "grid '" + grid->getName() + "' has no active voxels";
      return false;
    }
    // One voxel of background around the active ones, so that the density falls to the
    // background (zero for a density) at the dense grid's faces.
    const openvdb::Coord lo = active.min() - openvdb::Coord(1),
                         hi = active.max() + openvdb::Coord(1);
    const long long nx = hi.x() - lo.x() + 1, ny = hi.y() - lo.y() + 1, nz = hi.z() - lo.z() + 1;
    if (nx * ny > kMaxDenseValues / nz) {
      *problem = "grid '" + grid->getName() + "' spans " + std::to_string(nx) + " x " +
                 std::to_string(ny) + " x " + std::to_string(nz) +
                 " voxels: more than 2^27 once dense";
      return false;
    }
    medium->type = MediumDescription::Type::Grid;
    medium->nx = int(nx), medium->ny = int(ny), medium->nz = int(nz);
    medium->cellCentred = false;
    medium->density.assign(size_t(nx * ny * nz), 0.0f);
    const openvdb::FloatGrid::ConstAccessor access = grid->getConstAccessor();
    for (long long z = 0; z < nz; ++z)
      for (long long y = 0; y < ny; ++y)
        for (long long x = 0; x < nx; ++x) {
          const float v = access.getValue(lo + openvdb::Coord(int(x), int(y), int(z)));
          if (!(v >= 0) || !std::isfinite(v)) {
            *problem = "grid '" + grid->getName() + "' holds a density that is not finite and >= 0";
            return false;
          }
          medium->density[size_t((z * ny + y) * nx + x)] = v;
        }
    // OpenVDB's affine map takes row vectors (p' = p M); ours column vectors (p' = M p).
    const openvdb::math::Mat4d m = grid->transform().baseMap()->getAffineMap()->getMat4();
    Matrix4 indexToWorld;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) indexToWorld.m[r][c] = m(c, r);
    // The dense grid's corner samples at index points lo .. hi: the unit cube from there.
    const Vec3f extent(float(nx - 1), float(ny - 1), float(nz - 1));
    const Matrix4 unitToIndex =
        Matrix4::translate(Vec3f(float(lo.x()), float(lo.y()), float(lo.z()))) *
        Matrix4::scale(extent);
    medium->worldToGrid = (indexToWorld * unitToIndex).inverse();
    if (!medium->worldToGrid.isFinite()) {
      *problem = "grid '" + grid->getName() + "' has a singular transform";
      return false;
    }
    return true;
  } catch (const openvdb::Exception& e) {
    *problem = std::string("OpenVDB: ") + e.what();
    return false;
  } catch (const std::exception& e) {
    *problem = e.what();
    return false;
  }
}

}  // namespace farm
