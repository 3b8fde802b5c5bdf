#include "coordinator/flush_log.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"

namespace farm {
namespace {
namespace fs = std::filesystem;

std::string contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(FlushLog, ARecordCountsOnlyOnceItsRowCommitted) {
  testing::ScratchDir scratch("flush-log");
  uint64_t offset = 99;
  {
    FlushLog log(scratch.path());
    ASSERT_TRUE(log.open("job", 0).isOk());
    ASSERT_TRUE(log.write("job", "first", &offset).isOk());
    EXPECT_EQ(offset, 0u);
    log.commit("job", 5);
    // A record whose row did not commit: the next write goes where it went.
    ASSERT_TRUE(log.write("job", "lost", &offset).isOk());
    EXPECT_EQ(offset, 5u);
    ASSERT_TRUE(log.write("job", "second", &offset).isOk());
    EXPECT_EQ(offset, 5u);
    log.commit("job", 6);
    ASSERT_TRUE(log.write("job", "uncommitted", &offset).isOk());
    EXPECT_EQ(offset, 11u);
  }  // a crash before the last row committed
  EXPECT_EQ(contents(scratch / "job.log"), "firstseconduncommitted");
  FlushLog log(scratch.path());
  ASSERT_TRUE(log.open("job", 11).isOk());  // where the committed rows end
  EXPECT_EQ(contents(scratch / "job.log"), "firstsecond");
  FlushLog::Reader reader = log.reader("job");
  std::string record;
  ASSERT_TRUE(reader.read(5, 6, &record));
  EXPECT_EQ(record, "second");
  ASSERT_TRUE(reader.read(0, 5, &record));
  EXPECT_EQ(record, "first");
  EXPECT_FALSE(reader.read(5, 7, &record));  // past the end
}

TEST(FlushLog, AResetLogStartsAgainAtItsBeginning) {
  testing::ScratchDir scratch("flush-log");
  FlushLog log(scratch.path());
  uint64_t offset = 0;
  ASSERT_TRUE(log.open("job", 0).isOk());
  ASSERT_TRUE(log.write("job", "folded", &offset).isOk());
  log.commit("job", 6);
  log.reset("job");  // a checkpoint dropped every row
  EXPECT_FALSE(log.isOpen("job"));
  EXPECT_EQ(contents(scratch / "job.log"), "");
  ASSERT_TRUE(log.open("job", 0).isOk());
  ASSERT_TRUE(log.write("job", "next", &offset).isOk());
  EXPECT_EQ(offset, 0u);
}

TEST(FlushLog, AJobIdThatIsNoFileNameIsRefused) {
  testing::ScratchDir scratch("flush-log");
  FlushLog log(scratch.path());
  for (const std::string id : {"", "a/b", "..", "x..y"}) {
    EXPECT_FALSE(FlushLog::namesAFile(id)) << id;
    EXPECT_EQ(log.open(id, 0).code(), StatusCode::kInvalidArgument) << id;
    std::string name;
    EXPECT_EQ(log.writeFilm(id, 1, "film", &name).code(), StatusCode::kInvalidArgument) << id;
  }
  uint64_t offset = 0;
  EXPECT_FALSE(log.write("never-opened", "x", &offset).isOk());
}

TEST(FlushLog, OnlyTheFilmACommittedRecordNamesSurvives) {
  testing::ScratchDir scratch("flush-log");
  FlushLog log(scratch.path());
  std::string first, second, failed;
  ASSERT_TRUE(log.writeFilm("job", 3, "one", &first).isOk());
  log.adoptFilm("job", first);
  ASSERT_TRUE(log.writeFilm("job", 3, "two", &second).isOk());
  EXPECT_NE(first, second);
  EXPECT_TRUE(fs::exists(scratch / first));  // until the record naming `second` commits
  log.adoptFilm("job", second);
  EXPECT_FALSE(fs::exists(scratch / first));
  EXPECT_EQ(contents(scratch / second), "two");
  ASSERT_TRUE(log.writeFilm("job", 3, "three", &failed).isOk());
  log.discardFilm(failed);  // its record did not commit
  EXPECT_FALSE(fs::exists(scratch / failed));
  EXPECT_TRUE(fs::exists(scratch / second));

  // A restart: what a crash left (a film whose record never committed, a temporary file) goes;
  // the film the stored checkpoint names stays.
  std::ofstream(scratch / "job.0.7.sums") << "left by a crash";
  std::ofstream(scratch / "job.0.8.sums.tmp") << "left by a crash";
  std::ofstream(scratch / "job.log") << "a log is not a film";
  FlushLog restarted(scratch.path());
  restarted.knowFilm("job", second);
  restarted.sweep();
  EXPECT_FALSE(fs::exists(scratch / "job.0.7.sums"));
  EXPECT_FALSE(fs::exists(scratch / "job.0.8.sums.tmp"));
  EXPECT_TRUE(fs::exists(scratch / "job.log"));
  EXPECT_TRUE(fs::exists(scratch / second));

  restarted.removeJob("job");  // the job ended
  EXPECT_FALSE(fs::exists(scratch / "job.log"));
  EXPECT_FALSE(fs::exists(scratch / second));
}

}  // namespace
}  // namespace farm
