// Parallel snapshot I/O: every rank writes its part, and groups of 1, 2, 3 and all
// ranks (sub-communicators made with split) read the output back. Count and every
// value are conserved bit for bit, shares are balanced, failures are collective.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <pik/comm/Comm.hpp>
#include <pik/io/ParallelSnapshot.hpp>

namespace {

namespace io = pik::io;
pik::Comm world() { return pik::Comm::world(); }

constexpr std::uint64_t n_all = 1001;

// Particle k of the whole output, from its index alone (every rank can check it).
double value(std::uint64_t k, int field) { return std::sin(0.1 * double(k) + field) * std::pow(10.0, double(k % 7) - 3); }

// This rank's particles: every rank but the last takes a slice of uneven size
// (the last holds none when there are several ranks), ids scrambled.
io::Snapshot my_part(const pik::Comm& comm) {
  const int p = comm.size(), r = comm.rank();
  const int holders = p > 1 ? p - 1 : 1;
  io::Snapshot s;
  s.time = 0.125;
  s.step = 42;
  s.attr.set("theta", 0.5);
  s.attr.set("run", "parallel io test");
  auto& acc = s.column("Acceleration", 3);
  auto& pot = s.column("Potential", 1);
  (void)acc, (void)pot;
  if (r < holders) {
    // Slice boundaries at k^2 / holders^2 of the total: uneven on purpose.
    auto cut = [&](int k) { return n_all * std::uint64_t(k * k) / std::uint64_t(holders * holders); };
    for (std::uint64_t k = cut(r); k < cut(r + 1); ++k) {
      s.id.push_back(k * 2654435761u % 1000003u);
      s.mass.push_back(value(k, 0));
      s.pos.push_back({value(k, 1), value(k, 2), value(k, 3)});
      s.vel.push_back({value(k, 4), value(k, 5), value(k, 6)});
      for (int d = 0; d < 3; ++d) s.extra[0].data.push_back(value(k, 7 + d));
      s.extra[1].data.push_back(value(k, 10));
    }
  }
  return s;
}

// What the group `g` read: balanced shares in global order, every value exact.
void check_read(const io::Snapshot& s, const pik::Comm& g, const std::string& what) {
  const std::uint64_t lo = n_all * std::uint64_t(g.rank()) / std::uint64_t(g.size());
  const std::uint64_t hi = n_all * std::uint64_t(g.rank() + 1) / std::uint64_t(g.size());
  ASSERT_EQ(s.size(), hi - lo) << what;
  EXPECT_EQ(s.first_index, lo) << what;
  EXPECT_EQ(s.total(), n_all) << what;
  EXPECT_EQ(s.part, std::uint32_t(g.rank()));
  EXPECT_EQ(s.n_parts, std::uint32_t(g.size()));
  EXPECT_EQ(s.time, 0.125);
  EXPECT_EQ(s.step, 42u);
  EXPECT_EQ(s.attr.get_double("theta"), 0.5);
  EXPECT_EQ(s.attr.get_string("run"), "parallel io test");
  ASSERT_EQ(s.extra.size(), 2u);
  EXPECT_EQ(s.extra[0].name, "Acceleration");
  EXPECT_EQ(s.extra[1].components, 1);
  std::size_t bad = 0;
  for (std::uint64_t k = lo; k < hi; ++k) {
    const std::size_t i = std::size_t(k - lo);
    bad += s.id[i] != k * 2654435761u % 1000003u;
    bad += s.mass[i] != value(k, 0);
    bad += s.pos[i].x != value(k, 1) || s.pos[i].y != value(k, 2) || s.pos[i].z != value(k, 3);
    bad += s.vel[i].x != value(k, 4) || s.vel[i].y != value(k, 5) || s.vel[i].z != value(k, 6);
    for (int d = 0; d < 3; ++d) bad += s.extra[0].data[3 * i + std::size_t(d)] != value(k, 7 + d);
    bad += s.extra[1].data[i] != value(k, 10);
  }
  EXPECT_EQ(bad, 0u) << what;
  EXPECT_EQ(g.sum(std::uint64_t(s.size())), n_all) << what;
}

// A fresh directory shared by the ranks of this run (rank 0's pid names it).
std::string scratch_dir(const pik::Comm& comm, const std::string& tag) {
  const long pid = comm.broadcast(long(::getpid()), 0);
  const char* tmp = std::getenv("TMPDIR");
  const std::string dir = std::string(tmp ? tmp : "/tmp") + "/pik_io_mpi_" + tag + "_np" +
                          std::to_string(comm.size()) + "_" + std::to_string(pid);
  if (comm.is_root()) std::filesystem::create_directories(dir);
  comm.barrier();
  return dir;
}

void round_trip(io::Format format) {
  const auto comm = world();
  const std::string dir = scratch_dir(comm, io::format_name(format));
  const std::string path = dir + "/snap" + io::extension(format);
  io::write_snapshot_parallel(path, my_part(comm), format, comm);
  if (comm.is_root()) {
    // One file per rank (just `path` on one rank); the serial reader agrees.
    for (int r = 0; r < comm.size(); ++r)
      EXPECT_TRUE(std::filesystem::exists(io::part_path(path, std::uint32_t(r), std::uint32_t(comm.size()))));
    const io::Snapshot all = io::read_snapshot_parts(path);
    EXPECT_EQ(all.size(), n_all);
  }
  // Read back by groups of q ranks for q = 1, 2, 3 and all.
  for (int q : {1, 2, 3, comm.size()}) {
    if (q > comm.size()) continue;
    const auto group = comm.split(comm.rank() / q, comm.rank());
    const io::Snapshot s = io::read_snapshot_parallel(path, group);
    check_read(s, group, std::string(io::format_name(format)) + " written at np " + std::to_string(comm.size()) +
                             ", read at " + std::to_string(group.size()));
  }
  comm.barrier();
  if (comm.is_root()) std::filesystem::remove_all(dir);
}

}  // namespace

TEST(ParallelSnapshot, BinaryRoundTripAtAnyRankCount) { round_trip(io::Format::binary); }

TEST(ParallelSnapshot, AsciiRoundTripAtAnyRankCount) { round_trip(io::Format::ascii); }

TEST(ParallelSnapshot, Hdf5RoundTripAtAnyRankCount) {
  if (!io::have_hdf5) GTEST_SKIP() << "built without HDF5";
  round_trip(io::Format::hdf5);
}

TEST(ParallelSnapshot, AMissingPartFailsOnEveryRank) {
  const auto comm = world();
  if (comm.size() < 2) GTEST_SKIP() << "needs two parts";
  const std::string dir = scratch_dir(comm, "missing");
  const std::string path = dir + "/snap.pbin";
  io::write_snapshot_parallel(path, my_part(comm), io::Format::binary, comm);
  if (comm.is_root()) std::filesystem::remove(io::part_path(path, 1, std::uint32_t(comm.size())));
  comm.barrier();
  // Every rank throws (none waits forever in a collective), naming the missing file.
  try {
    (void)io::read_snapshot_parallel(path, comm);
    ADD_FAILURE() << "reading an output with a missing part did not fail";
  } catch (const io::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("snap.1.pbin"), std::string::npos) << e.what();
  }
  comm.barrier();
  if (comm.is_root()) std::filesystem::remove_all(dir);
}

TEST(ParallelSnapshot, RanksMustAgreeOnTheHeader) {
  const auto comm = world();
  if (comm.size() < 2) GTEST_SKIP() << "needs two ranks";
  const std::string dir = scratch_dir(comm, "header");
  io::Snapshot s = my_part(comm);
  if (comm.rank() == 1) s.step = 43;
  EXPECT_THROW(io::write_snapshot_parallel(dir + "/snap.pbin", s, io::Format::binary, comm), io::IoError);
  comm.barrier();
  if (comm.is_root()) std::filesystem::remove_all(dir);
}
