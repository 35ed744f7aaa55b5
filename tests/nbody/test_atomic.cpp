// Atomic writes: a failed or killed writer never leaves a half-written destination.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include <pik/io/AtomicFile.hpp>
#include <pik/io/SnapshotIo.hpp>

#include "TempDir.hpp"

namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

pik::io::Snapshot particles(std::size_t n, double time) {
  pik::io::Snapshot s;
  s.resize(n);
  s.time = time;
  for (std::size_t i = 0; i < n; ++i) {
    s.id[i] = i;
    s.mass[i] = 1.0 / double(n);
    s.pos[i] = {double(i), time, -double(i)};
  }
  return s;
}

}  // namespace

TEST(AtomicFile, CommitPublishesAndLeavesNoTemporary) {
  pik_test::TempDir dir;
  const std::string path = dir.file("out.txt");
  {
    pik::io::AtomicFile f(path);
    f.write("hello ");
    EXPECT_FALSE(std::filesystem::exists(path));  // invisible until committed
    f.write("world");
    f.commit();
  }
  EXPECT_EQ(read_text(path), "hello world");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, AbandonedWriteKeepsTheOldFile) {
  pik_test::TempDir dir;
  const std::string path = dir.file("out.txt");
  {
    pik::io::AtomicFile f(path);
    f.write("old");
    f.commit();
  }
  {
    pik::io::AtomicFile f(path);
    f.write("new but never committed");
  }
  EXPECT_EQ(read_text(path), "old");
  // An exception while a by-name writer (HDF5) fills its temporary file.
  EXPECT_THROW(pik::io::write_atomically_by_name(path,
                                                 [](const std::string& tmp) {
                                                   std::ofstream(tmp) << "partial";
                                                   throw std::runtime_error("disk on fire");
                                                 }),
               std::runtime_error);
  EXPECT_EQ(read_text(path), "old");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFile, UnwritableDirectoryIsReported) {
  try {
    pik::io::AtomicFile f("/nonexistent-pik-dir/snap.pbin");
    ADD_FAILURE() << "no error";
  } catch (const pik::io::IoError& e) {
    EXPECT_EQ(e.path(), "/nonexistent-pik-dir/snap.pbin");
    EXPECT_NE(e.reason().find("cannot create a temporary file"), std::string::npos) << e.what();
  }
}

// A writer killed half way (here by the file-size limit, SIGXFSZ, as a full disk or a
// crash would stop it) leaves the previous snapshot complete and readable.
TEST(AtomicFile, KilledWriterLeavesPreviousSnapshotIntact) {
  pik_test::TempDir dir;
  for (pik::io::Format format : {pik::io::Format::binary, pik::io::Format::ascii}) {
    const std::string path = dir.file(std::string("snap") + pik::io::extension(format));
    const pik::io::Snapshot old = particles(100, 1.0);
    pik::io::write_snapshot(path, old, format);
    const auto old_size = std::filesystem::file_size(path);

    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      rlimit lim{};
      lim.rlim_cur = lim.rlim_max = rlim_t(old_size + 4096);  // far less than the new file
      ::setrlimit(RLIMIT_FSIZE, &lim);
      ::signal(SIGXFSZ, SIG_DFL);
      pik::io::write_snapshot(path, particles(200000, 2.0), format);
      ::_exit(0);  // not reached: the write is killed
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the writer was expected to be killed";
    EXPECT_EQ(WTERMSIG(status), SIGXFSZ);

    const pik::io::Snapshot back = pik::io::read_snapshot(path);
    EXPECT_TRUE(pik::io::same_bits(back, old)) << pik::io::format_name(format);
    // The killed writer's hidden temporary file is all that remains of it.
    for (const auto& e : dir.entries())
      if (e.rfind(".snap", 0) == 0) std::filesystem::remove(dir.file(e));
  }
}
