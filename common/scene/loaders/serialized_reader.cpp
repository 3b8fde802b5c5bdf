#include "common/scene/loaders/serialized_reader.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace farm {

namespace {

constexpr uint16_t kMagic = 0x041C;
constexpr uint16_t kVersion3 = 3, kVersion4 = 4;
constexpr uint32_t kHasNormals = 0x0001, kHasTexcoords = 0x0002, kHasColors = 0x0008,
                   kFaceNormals = 0x0010, kSinglePrecision = 0x1000, kDoublePrecision = 0x2000;

[[noreturn]] void fail(const std::string& why) {
  throw std::runtime_error(why);
}

template <typename T>
T readLittleEndian(const unsigned char* p) {
  T v = 0;
  for (size_t i = 0; i < sizeof(T); ++i) v |= T(T(p[i]) << (8 * i));
  return v;
}

// The zlib stream of one mesh, read on demand: a corrupt or truncated stream is an error at the
// read that needs the missing bytes, and nothing is inflated beyond what the counts call for.
class Inflater {
 public:
  Inflater(const unsigned char* data, size_t size) {
    std::memset(&z_, 0, sizeof(z_));
    if (inflateInit(&z_) != Z_OK) fail("cannot start zlib");
    z_.next_in = const_cast<unsigned char*>(data);
    // zlib counts its input in 32 bits; larger meshes are read in slices below.
    remaining_ = size;
    feed();
  }
  ~Inflater() { inflateEnd(&z_); }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  void read(void* out, size_t n, const char* what) {
    auto* dst = static_cast<unsigned char*>(out);
    while (n > 0) {
      const size_t slice = std::min<size_t>(n, 1u << 30);
      z_.next_out = dst;
      z_.avail_out = uInt(slice);
      while (z_.avail_out > 0) {
        feed();
        const int rc = inflate(&z_, Z_NO_FLUSH);
        if (rc == Z_STREAM_END) {
          if (z_.avail_out > 0) fail(std::string("the mesh's data ends inside its ") + what);
          break;
        }
        // No progress with all the input given: the file stops inside the stream.
        if (rc == Z_BUF_ERROR && z_.avail_in == 0 && remaining_ == 0)
          fail(std::string("the file ends inside the mesh's ") + what);
        if (rc != Z_OK)
          fail(std::string("corrupt compressed data in the mesh's ") + what +
               (z_.msg ? std::string(" (") + z_.msg + ")" : std::string()));
      }
      dst += slice;
      n -= slice;
    }
  }

  // The stream's end, which carries its checksum (adler32): corruption that still decodes into
  // plausible numbers is caught here.
  void finish() {
    unsigned char extra;
    z_.next_out = &extra;
    z_.avail_out = 1;
    feed();
    const int rc = inflate(&z_, Z_FINISH);
    if (rc == Z_STREAM_END && z_.avail_out == 1) return;
    if (z_.avail_out == 0) fail("the mesh's stream holds more data than its counts call for");
    if (rc == Z_BUF_ERROR && z_.avail_in == 0 && remaining_ == 0)
      fail("the file ends before the mesh's stream does");
    fail(std::string("corrupt compressed data at the mesh's end") +
         (z_.msg ? std::string(" (") + z_.msg + ")" : std::string()));
  }

 private:
  void feed() {
    if (z_.avail_in > 0 || remaining_ == 0) return;
    const size_t slice = std::min<size_t>(remaining_, 1u << 30);
    z_.avail_in = uInt(slice);
    remaining_ -= slice;
  }

  z_stream z_;
  size_t remaining_ = 0;
};

// count values of `doubles ? double : float`, little-endian, as floats (finite ones only).
std::vector<float> readReals(Inflater& in, size_t count, bool doubles, const char* what) {
  const size_t width = doubles ? 8 : 4;
  std::vector<unsigned char> raw(count * width);
  in.read(raw.data(), raw.size(), what);
  std::vector<float> out(count);
  for (size_t i = 0; i < count; ++i) {
    const unsigned char* p = raw.data() + i * width;
    double v;
    if (doubles) {
      const uint64_t bits = readLittleEndian<uint64_t>(p);
      std::memcpy(&v, &bits, 8);
    } else {
      const uint32_t bits = readLittleEndian<uint32_t>(p);
      float f;
      std::memcpy(&f, &bits, 4);
      v = f;
    }
    if (!std::isfinite(v) || std::fabs(v) > 3.0e38)
      fail(std::string("a non-finite or out-of-range value among the mesh's ") + what);
    out[i] = float(v);
  }
  return out;
}

}  // namespace

SerializedMesh parseSerialized(const std::string& bytes, int shapeIndex, size_t maxElements) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t size = bytes.size();
  if (size < 4) fail("too short to be a Mitsuba serialized mesh");
  const uint16_t magic = readLittleEndian<uint16_t>(data);
  if (magic == 0x1C04)
    fail("a serialized mesh of an old Mitsuba version (byte-swapped header); re-export it");
  if (magic != kMagic) fail("not a Mitsuba serialized mesh (no 0x041C header)");
  const uint16_t version = readLittleEndian<uint16_t>(data + 2);
  if (version != kVersion3 && version != kVersion4)
    fail("serialized mesh version " + std::to_string(version) + " is not supported (3 or 4)");
  if (shapeIndex < 0) fail("shapeIndex must be >= 0");

  // The mesh's start: 0 for the first; the others from the dictionary at the file's end.
  size_t start = 0;
  if (shapeIndex > 0) {
    if (size < 8) fail("the file has no mesh dictionary at its end");
    const uint32_t count = readLittleEndian<uint32_t>(data + size - 4);
    if (uint32_t(shapeIndex) >= count)
      fail("shapeIndex " + std::to_string(shapeIndex) + " is beyond the file's " +
           std::to_string(count) + " meshes");
    const size_t entry = version == kVersion4 ? 8 : 4;
    if (size_t(count) * entry + 4 > size) fail("the mesh dictionary is longer than the file");
    const unsigned char* p = data + size - 4 - size_t(count - uint32_t(shapeIndex)) * entry;
    const uint64_t offset =
        version == kVersion4 ? readLittleEndian<uint64_t>(p) : readLittleEndian<uint32_t>(p);
    if (offset > size - 4)
      fail("the dictionary's offset of mesh " + std::to_string(shapeIndex) + " is beyond the file");
    start = size_t(offset);
    if (readLittleEndian<uint16_t>(data + start) != kMagic ||
        readLittleEndian<uint16_t>(data + start + 2) != version)
      fail("the dictionary's offset of mesh " + std::to_string(shapeIndex) +
           " does not point at a mesh header");
  }

  Inflater in(data + start + 4, size - start - 4);
  unsigned char word[8];
  in.read(word, 4, "flags");
  const uint32_t flags = readLittleEndian<uint32_t>(word);
  const bool doubles = (flags & kDoublePrecision) != 0;
  if (doubles == ((flags & kSinglePrecision) != 0))
    fail("the mesh's flags give neither or both of single and double precision");
  if (version == kVersion4) {
    // The name, null-terminated: read and dropped (shapes are named by their scene line).
    for (size_t n = 0;; ++n) {
      char c;
      in.read(&c, 1, "name");
      if (c == '\0') break;
      if (n > 4096) fail("the mesh's name is longer than 4096 bytes");
    }
  }
  in.read(word, 8, "vertex count");
  const uint64_t vertexCount = readLittleEndian<uint64_t>(word);
  in.read(word, 8, "triangle count");
  const uint64_t triangleCount = readLittleEndian<uint64_t>(word);
  if (vertexCount == 0 || triangleCount == 0) fail("the mesh has no vertices or no triangles");
  if (vertexCount > maxElements || triangleCount > maxElements / 3 ||
      vertexCount + 3 * triangleCount > maxElements)
    fail("the mesh's " + std::to_string(vertexCount) + " vertices and " +
         std::to_string(triangleCount) + " triangles exceed the scene's budget");
  const size_t nv = size_t(vertexCount), nt = size_t(triangleCount);

  SerializedMesh mesh;
  mesh.faceNormals = (flags & kFaceNormals) != 0;
  std::vector<float> p = readReals(in, 3 * nv, doubles, "positions");
  mesh.positions.resize(nv);
  for (size_t i = 0; i < nv; ++i) mesh.positions[i] = Vec3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
  if (flags & kHasNormals) {
    std::vector<float> n = readReals(in, 3 * nv, doubles, "normals");
    mesh.normals.resize(nv);
    for (size_t i = 0; i < nv; ++i) mesh.normals[i] = Vec3f(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
  }
  if (flags & kHasTexcoords) {
    std::vector<float> t = readReals(in, 2 * nv, doubles, "texture coordinates");
    mesh.uvs.resize(nv);
    for (size_t i = 0; i < nv; ++i) mesh.uvs[i] = Vec2f(t[2 * i], t[2 * i + 1]);
  }
  if (flags & kHasColors) readReals(in, 3 * nv, doubles, "vertex colours");  // unused
  std::vector<unsigned char> raw(3 * nt * 4);
  in.read(raw.data(), raw.size(), "triangles");
  mesh.indices.resize(3 * nt);
  for (size_t i = 0; i < 3 * nt; ++i) {
    const uint32_t index = readLittleEndian<uint32_t>(raw.data() + 4 * i);
    if (index >= nv)
      fail("triangle " + std::to_string(i / 3) + " names vertex " + std::to_string(index) + " of " +
           std::to_string(nv));
    mesh.indices[i] = index;
  }
  in.finish();
  return mesh;
}

}  // namespace farm
