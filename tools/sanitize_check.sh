#!/usr/bin/env bash
# The sanitize preset (ASan and UBSan, leaks included) over what takes hostile input: the fuzz
# corpora (every scene loader, the bundle manifest, every coordinator request), the coordinator's
# unit tests, and the scene-loading, BSDF and mutation tests. About 45 minutes of building on two
# cores the first time (build-sanitize/, ccache), then about 6 of tests.
#
#   tools/sanitize_check.sh            # the set above
#   tools/sanitize_check.sh --all      # the whole suite under the sanitizers (hours)
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset sanitize
if [[ "${1:-}" == "--all" ]]; then
  cmake --build --preset sanitize
  exec ctest --preset sanitize
fi
cmake --build --preset sanitize --target fuzz_scene_loader fuzz_bundle_manifest fuzz_requests \
  common_tests farm_unit_tests
ctest --preset sanitize -R '^Fuzz\.'
build-sanitize/bin/farm_unit_tests
build-sanitize/bin/common_tests --gtest_filter='*Loader*:*Ply*:*Pbrt*:*Mitsuba*:*Tokenizer*:*Serialized*:*Vdb*:*Texture*:*Image*:*Bsdf*:*Matrix*:*Mutation*:*Manifold*:*Bootstrap*'
