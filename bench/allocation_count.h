#pragma once
// The bytes operator new has handed out in this process so far: allocation_count.cpp replaces
// the global operator new of the benchmark that links it, to count them (a separate translation
// unit, so that no caller sees the replacement's malloc beside its delete).
#include <cstdint>

namespace farm {

int64_t allocatedBytes();

}  // namespace farm
