// renderLocally under a time budget: the chains take turns of one flush each, so that every
// chain advances as far as the others, within one flush. Run to the deadline instead, the first
// chain on each thread kept it until the time was up and the others ran one flush each after
// it: the image was a few chains', stopped at a time that depended on where they had gone.
#include "common/render/local_render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;

TEST(LocalRender, ChainsTakeTurnsUnderATimeBudget) {
  RenderSettings settings;
  settings.width = settings.height = 32;
  auto scene = loadScene(kShared + "/scenes/cornell-box/scene.xml", settings);
  for (Algorithm algorithm : {Algorithm::PSSMLT, Algorithm::MLT}) {
    settings.algorithm = algorithm;
    settings.numChains = 16;
    settings.timeBudgetSeconds = 2;
    settings.flushInterval = 1024;
    settings.seed = 5;
    const LocalRenderResult r = renderLocally(RenderJob(scene, settings, "turns"));
    ASSERT_EQ(r.chainWork.size(), 16u);
    const auto [least, most] = std::minmax_element(r.chainWork.begin(), r.chainWork.end());
    std::printf("%s: %lld to %lld mutations a chain, %lld in all\n", algorithmName(algorithm),
                static_cast<long long>(*least), static_cast<long long>(*most),
                static_cast<long long>(r.work));
    EXPECT_GE(*least, 4 * settings.flushInterval) << "every chain takes several turns";
    EXPECT_LE(*most - *least, settings.flushInterval) << "the turns are one flush each";
    EXPECT_EQ(std::accumulate(r.chainWork.begin(), r.chainWork.end(), int64_t(0)), r.work);
  }
}

}  // namespace
}  // namespace farm
