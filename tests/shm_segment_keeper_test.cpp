// transport/fastdds/shm_segment_keeper.hpp on files of a temporary folder that stand for Fast DDS's
// (a data segment fastrtps_<hex> this process maps, its lock file fastrtps_<hex>_el flocked): a
// segment kept before its owner's participant is deleted gets its name back, with its contents,
// after Fast DDS removed it; old restored names go, fresh ones stay unless their owner is named.

#include "transport/fastdds/shm_segment_keeper.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <string>

#include "test_support.hpp"

namespace tessera::transport {
namespace {

const std::string kName = "fastrtps_0123456789abcdef";

bool exists(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0;
}

std::string contents(const std::string& path) {
  std::ifstream f(path);
  std::string s;
  std::getline(f, s);
  return s;
}

// A segment of this process: the file mapped, its lock file flocked (as Fast DDS holds it).
struct OwnSegment {
  explicit OwnSegment(const std::string& dir) {
    const std::string path = dir + "/" + kName;
    std::ofstream(path) << "message of the deleted participant\n";
    data_fd = open(path.c_str(), O_RDONLY);
    map = mmap(nullptr, 4096, PROT_READ, MAP_SHARED, data_fd, 0);
    lock_fd = open((path + "_el").c_str(), O_RDWR | O_CREAT, 0644);
    flock(lock_fd, LOCK_EX);
  }
  // What deleting the participant does to the files.
  void delete_participant(const std::string& dir) {
    munmap(map, 4096);
    close(data_fd);
    unlink((dir + "/" + kName).c_str());
    close(lock_fd);
    unlink((dir + "/" + kName + "_el").c_str());
  }
  int data_fd = -1, lock_fd = -1;
  void* map = nullptr;
};

TEST(ShmSegmentKeeper, FindsTheSegmentsThisProcessMapsAndHoldsTheLockOf) {
  const std::string dir = test::temp_dir();
  std::ofstream(dir + "/fastrtps_fedcba9876543210") << "a peer's segment, not mapped\n";
  OwnSegment own(dir);
  EXPECT_EQ(own_shm_segments(dir), std::vector<std::string>{kName});
  own.delete_participant(dir);
  EXPECT_TRUE(own_shm_segments(dir).empty());
}

TEST(ShmSegmentKeeper, APeersSegmentThisProcessMapsIsNotItsOwn) {
  // A live peer's segment: mapped here (to write to the peer) and its lock file open here, but
  // the lock held by the peer's process.
  const std::string dir = test::temp_dir();
  const std::string path = dir + "/" + kName;
  std::ofstream(path) << "a live peer's segment\n";
  const int data_fd = open(path.c_str(), O_RDONLY);
  void* map = mmap(nullptr, 4096, PROT_READ, MAP_SHARED, data_fd, 0);
  const int lock_fd = open((path + "_el").c_str(), O_RDWR | O_CREAT, 0644);
  int locked[2], release[2];
  ASSERT_EQ(pipe(locked), 0);
  ASSERT_EQ(pipe(release), 0);
  const pid_t peer = fork();
  ASSERT_GE(peer, 0);
  if (peer == 0) {
    const int fd = open((path + "_el").c_str(), O_RDWR);
    char c = flock(fd, LOCK_EX) == 0 ? 'y' : 'n';
    if (write(locked[1], &c, 1) != 1 || read(release[0], &c, 1) != 1) _exit(1);
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(read(locked[0], &c, 1), 1);
  ASSERT_EQ(c, 'y');
  EXPECT_TRUE(own_shm_segments(dir).empty());
  ASSERT_EQ(write(release[1], &c, 1), 1);
  int status = 0;
  waitpid(peer, &status, 0);
  EXPECT_EQ(status, 0);
  munmap(map, 4096);
  for (int fd : {data_fd, lock_fd, locked[0], locked[1], release[0], release[1]}) close(fd);
}

TEST(ShmSegmentKeeper, ADeletedParticipantsSegmentGetsItsNameAndContentsBack) {
  const std::string dir = test::temp_dir();
  OwnSegment own(dir);
  ShmSegmentKeeper keeper(dir);
  keeper.keep();
  own.delete_participant(dir);
  EXPECT_FALSE(exists(dir + "/" + kName));
  EXPECT_EQ(keeper.restore(), std::vector<std::string>{kName});
  EXPECT_EQ(contents(dir + "/" + kName), "message of the deleted participant");
  EXPECT_EQ(contents(dir + "/tessera_kept_0123456789abcdef"), std::to_string(getpid()));
  // No link left behind; a fresh restored name stays through a sweep with a 10 s life.
  EXPECT_EQ(sweep_kept_segments(dir, 10.0), 0);
  EXPECT_TRUE(exists(dir + "/" + kName));
  // Named by its owner (launch at the end of a run), or old enough, it goes with its marker.
  EXPECT_EQ(sweep_kept_segments(dir, 10.0, {static_cast<int>(getpid())}), 1);
  EXPECT_FALSE(exists(dir + "/" + kName));
  EXPECT_FALSE(exists(dir + "/tessera_kept_0123456789abcdef"));
}

TEST(ShmSegmentKeeper, ALiveParticipantsSegmentIsLeftAsItIs) {
  const std::string dir = test::temp_dir();
  OwnSegment own(dir);
  ShmSegmentKeeper keeper(dir);
  keeper.keep();
  EXPECT_TRUE(keeper.restore().empty());  // another participant of this process was deleted
  EXPECT_TRUE(exists(dir + "/" + kName));
  EXPECT_FALSE(exists(dir + "/tessera_kept_0123456789abcdef"));
  EXPECT_EQ(sweep_kept_segments(dir, 0.0), 0);
  EXPECT_TRUE(exists(dir + "/" + kName));
  own.delete_participant(dir);
}

// Two participants of one process deleted at once: each keeper links the process's segments;
// the deleted one gets its name back once, with its marker, and no link is left.
TEST(ShmSegmentKeeper, TwoKeepersOfOneProcessRestoreADeletedSegmentOnce) {
  const std::string dir = test::temp_dir();
  OwnSegment own(dir);
  ShmSegmentKeeper first(dir), second(dir);
  first.keep();
  second.keep();
  own.delete_participant(dir);
  EXPECT_EQ(first.restore(), std::vector<std::string>{kName});
  EXPECT_TRUE(second.restore().empty());
  EXPECT_EQ(contents(dir + "/" + kName), "message of the deleted participant");
  EXPECT_TRUE(exists(dir + "/tessera_kept_0123456789abcdef"));
  EXPECT_EQ(sweep_kept_segments(dir, 0.0), 1);
  EXPECT_FALSE(exists(dir + "/" + kName));
}

}  // namespace
}  // namespace tessera::transport
