#pragma once
// Fixed-size values in and out of a byte string, the form of the chains' states (resumed bit for
// bit on any host of the farm, all little-endian x86-64 or ARM64).
#include <cstring>
#include <string>
#include <type_traits>

namespace farm {

template <typename T>
void appendBytes(std::string& s, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// Reads the next value at `at` and advances it; false (and nothing read) past the end.
template <typename T>
bool readBytes(const std::string& s, size_t& at, T* v) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (at > s.size() || s.size() - at < sizeof(T)) return false;
  std::memcpy(v, s.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

}  // namespace farm
