#pragma once
// One fuzz target per file: LLVMFuzzerTestOneInput over one input surface of the farm. Linked
// with libFuzzer (FARM_FUZZ=ON, clang) it is fuzzed; linked with corpus_driver.cpp it runs a
// corpus once, which ctest does (under the sanitize preset: every input with ASan and UBSan).
// A clear error for a bad input is the expected outcome; a crash, a sanitizer report or a leak
// is the finding.
#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
