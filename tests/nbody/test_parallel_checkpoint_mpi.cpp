// Checkpoints over ranks (io/ParallelCheckpoint.hpp) and the decomposition state
// they carry (DomainInfo::state): at the same rank count every rank gets its own
// part back bit for bit, attributes included; at another count equal shares; a
// snapshot, or parts of different steps, are refused on every rank; a restored
// DomainInfo decomposes as the original does.
#include <gtest/gtest.h>

#include <stdlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <pik/Vec.hpp>
#include <pik/comm/Comm.hpp>
#include <pik/domain/DomainInfo.hpp>
#include <pik/io/ParallelCheckpoint.hpp>

namespace {

namespace io = pik::io;
pik::Comm world() { return pik::Comm::world(); }

// One directory for all ranks: rank 0 makes it, everyone learns its name.
class SharedDir {
 public:
  explicit SharedDir(const pik::Comm& comm) : comm_(comm) {
    std::vector<char> name;
    if (comm.is_root()) {
      std::string templ = testing::TempDir() + "pik_pchk_XXXXXX";
      std::vector<char> buf(templ.begin(), templ.end());
      buf.push_back('\0');
      if (!::mkdtemp(buf.data())) std::abort();
      name.assign(buf.begin(), buf.end() - 1);
    }
    comm.broadcast(name, 0);
    path_.assign(name.begin(), name.end());
  }
  ~SharedDir() {
    comm_.barrier();
    if (comm_.is_root()) std::filesystem::remove_all(path_);
  }
  std::string file(const std::string& n) const { return path_ + "/" + n; }

 private:
  pik::Comm comm_;
  std::string path_;
};

// Rank r holds 3r + 1 particles (the last rank none, when there are several),
// values from (rank, index), and its own attribute.
io::Snapshot my_state(const pik::Comm& comm, std::uint64_t step) {
  const int r = comm.rank();
  io::Snapshot s;
  s.time = 0.5 * double(step);
  s.step = step;
  s.attr.set("E0", -0.25);
  s.attr.set("my_cost", double(r) * 1e3 + 0.1);
  auto& pot = s.column("Potential", 1);
  const int n = (comm.size() > 1 && r == comm.size() - 1) ? 0 : 3 * r + 1;
  for (int i = 0; i < n; ++i) {
    const double v = std::sin(double(r * 100 + i) + double(step));
    s.id.push_back(std::uint64_t(r * 100 + i));
    s.mass.push_back(v);
    s.pos.push_back({v, 2 * v, 3 * v});
    s.vel.push_back({-v, v / 3, v * 1e-9});
    pot.data.push_back(v / 7);
  }
  return s;
}

std::uint64_t total(const pik::Comm& comm) {
  std::uint64_t n = 0;
  for (int r = 0; r < comm.size(); ++r) n += (comm.size() > 1 && r == comm.size() - 1) ? 0 : 3 * r + 1;
  return n;
}

TEST(ParallelCheckpoint, SameRankCountGetsItsOwnPartBitForBit) {
  const auto comm = world();
  SharedDir dir(comm);
  const auto path = dir.file("checkpoint.pbin");
  io::Snapshot mine = my_state(comm, 8);
  io::write_checkpoint_parallel(path, mine, comm);
  const auto [back, exact] = io::read_checkpoint_parallel(path, comm, {"Potential"}, {"E0"});
  EXPECT_TRUE(exact);
  mine.first_index = back.first_index, mine.n_total = back.n_total;
  mine.part = back.part, mine.n_parts = back.n_parts;
  mine.attr.set(io::checkpoint_kind_key, io::checkpoint_kind);
  EXPECT_TRUE(io::same_bits(mine, back)) << "rank " << comm.rank();
  EXPECT_EQ(back.attr.get_double("my_cost"), double(comm.rank()) * 1e3 + 0.1);
  EXPECT_EQ(back.total(), total(comm));
}

TEST(ParallelCheckpoint, AnotherRankCountGetsEqualShares) {
  const auto comm = world();
  if (comm.size() == 1) GTEST_SKIP() << "needs two ranks or more";
  SharedDir dir(comm);
  const auto path = dir.file("checkpoint.pbin");
  io::write_checkpoint_parallel(path, my_state(comm, 3), comm);
  // Rank 0 alone, and the others together, read the checkpoint of all ranks.
  const auto group = comm.split(comm.rank() == 0 ? 0 : 1, comm.rank());
  const auto [back, exact] = io::read_checkpoint_parallel(path, group, {"Potential"});
  EXPECT_FALSE(exact);
  const std::uint64_t n = total(comm);
  EXPECT_EQ(back.size(), n * std::uint64_t(group.rank() + 1) / std::uint64_t(group.size()) -
                             n * std::uint64_t(group.rank()) / std::uint64_t(group.size()));
  EXPECT_EQ(group.sum(std::uint64_t(back.size())), n);
  EXPECT_EQ(back.step, 3u);
  EXPECT_EQ(back.attr.get_double("my_cost"), 0.1);  // part 0's
}

TEST(ParallelCheckpoint, RefusesSnapshotsAndMixedSteps) {
  const auto comm = world();
  SharedDir dir(comm);
  const auto snap = dir.file("snap.pbin");
  io::write_snapshot_parallel(snap, my_state(comm, 1), io::Format::binary, comm);
  try {
    (void)io::read_checkpoint_parallel(snap, comm);
    ADD_FAILURE() << "a snapshot was read as a checkpoint";
  } catch (const io::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("not a checkpoint"), std::string::npos) << e.what();
  }
  if (comm.size() == 1) return;
  // Step 1 everywhere, then step 2 everywhere but part 0 put back: a crash between renames.
  const auto path = dir.file("checkpoint.pbin");
  io::write_checkpoint_parallel(path, my_state(comm, 1), comm);
  const auto p0 = io::part_path(path, 0, std::uint32_t(comm.size()));
  if (comm.is_root()) std::filesystem::copy_file(p0, dir.file("old"));
  comm.barrier();
  io::write_checkpoint_parallel(path, my_state(comm, 2), comm);
  if (comm.is_root()) std::filesystem::rename(dir.file("old"), p0);
  comm.barrier();
  try {
    (void)io::read_checkpoint_parallel(path, comm);
    ADD_FAILURE() << "parts of steps 1 and 2 were read as one checkpoint";
  } catch (const io::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("different steps"), std::string::npos) << e.what();
  }
}

TEST(ParallelCheckpoint, ExactDoublesInAttributes) {
  const std::vector<double> v = {0.1, -0.0, 1e-310, std::numeric_limits<double>::infinity(),
                                 -std::numeric_limits<double>::infinity(), 12345678901234567.0,
                                 std::nextafter(1.0, 2.0)};
  const auto back = io::decode_exact(io::encode_exact(v), "test");
  ASSERT_EQ(back.size(), v.size());
  EXPECT_EQ(std::memcmp(back.data(), v.data(), v.size() * sizeof(double)), 0);
  EXPECT_TRUE(io::decode_exact("", "test").empty());
  EXPECT_THROW((void)io::decode_exact("0x1p+0 x", "test"), io::IoError);
}

struct P {
  pik::Vec3<double> pos;
};

TEST(DomainState, RestoredDecompositionContinuesIdentically) {
  const auto comm = world();
  std::mt19937_64 rng(77 + std::uint64_t(comm.rank()));
  std::normal_distribution<double> g;
  std::vector<P> ps(5000);  // more than the samples, so sampling is random
  for (auto& p : ps) p.pos = {g(rng), g(rng), g(rng)};
  pik::DomainInfo<double, 3>::Options opt;
  opt.smoothing = 0.5;  // the next cuts depend on the stored ones
  pik::DomainInfo<double, 3> a(comm, opt), b(comm, opt), fresh(comm, opt);
  a.decompose(ps, 1.0 + comm.rank());
  b.restore_state(a.state());
  EXPECT_EQ(b.decompositions(), 1);
  a.decompose(ps, 2.0);
  b.decompose(ps, 2.0);
  fresh.decompose(ps, 2.0);
  EXPECT_EQ(a.state(), b.state());
  if (comm.size() > 1) {
    EXPECT_NE(a.state(), fresh.state()) << "the state made no difference";
  }
  for (int r = 0; r < comm.size(); ++r)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(a.domain(r).lo[d], b.domain(r).lo[d]);
}

}  // namespace
