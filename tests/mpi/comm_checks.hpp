// Checks of the typed communicator front end that hold for any rank count; run
// under MPI by test_comm_mpi and on the serial backend by test_comm_serial.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include <pik/Vec.hpp>
#include <pik/comm/Comm.hpp>

namespace pik_test {

struct Payload {
  std::int64_t id;
  double value;
  float tag[3];
};

template <class C>
void check_reductions(const C& comm) {
  const int r = comm.rank(), p = comm.size();
  EXPECT_EQ(comm.sum(1), p);
  EXPECT_EQ(comm.sum(std::int64_t{1} << 40), std::int64_t(p) << 40);
  EXPECT_EQ(comm.sum(std::uint64_t(r)), std::uint64_t(p) * std::uint64_t(p - 1) / 2);
  EXPECT_EQ(comm.min(double(r) + 0.5), 0.5);
  EXPECT_EQ(comm.max(float(r)), float(p - 1));
  // With location: the value and the lowest rank holding it.
  const auto lo = comm.min_loc(double(10 - (r % 3)));
  EXPECT_EQ(lo.value, double(10 - std::min(2, p - 1)));
  EXPECT_EQ(lo.rank, std::min(2, p - 1));
  const auto hi = comm.max_loc(std::int64_t(r == p - 1 ? 99 : r));
  EXPECT_EQ(hi.value, 99);
  EXPECT_EQ(hi.rank, p - 1);
  const auto tie = comm.max_loc(7);
  EXPECT_EQ(tie.rank, 0);
  // Exact 64-bit integers beyond double's 53-bit mantissa.
  const auto big = comm.max_loc(static_cast<std::int64_t>((1ll << 62) + (r == 0 ? 1 : 0)));
  EXPECT_EQ(big.value, (1ll << 62) + 1);
  EXPECT_EQ(big.rank, 0);
  // Vectors component-wise, arrays in place.
  const auto v = comm.sum(pik::Vec3<double>{1.0, double(r), -2.0});
  EXPECT_EQ(v.x, double(p));
  EXPECT_EQ(v.y, double(p) * (p - 1) / 2);
  EXPECT_EQ(v.z, -2.0 * p);
  std::vector<int> a{r, -r, 1};
  comm.reduce_inplace(std::span<int>(a), pik::comm::ReduceOp::max);
  EXPECT_EQ(a, (std::vector<int>{p - 1, 0, 1}));
}

template <class C>
void check_broadcast_gather(const C& comm) {
  const int r = comm.rank(), p = comm.size();
  const int root = p - 1;
  EXPECT_EQ(comm.broadcast(r * 10 + 3, root), root * 10 + 3);
  std::vector<Payload> v;
  if (r == root) v = {{1, 2.5, {1, 2, 3}}, {-4, 1e300, {0, 0, 7}}};
  comm.broadcast(v, root);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[1].id, -4);
  EXPECT_EQ(v[1].value, 1e300);
  EXPECT_EQ(v[1].tag[2], 7.0f);

  const auto g = comm.gather(Payload{r, r * 0.5, {0, 0, 0}}, 0);
  if (comm.is_root()) {
    ASSERT_EQ(g.size(), std::size_t(p));
    for (int i = 0; i < p; ++i) EXPECT_EQ(g[i].id, i);
  } else {
    EXPECT_TRUE(g.empty());
  }
  // Rank i sends i elements (rank 0 sends none).
  std::vector<int> mine(static_cast<std::size_t>(r));
  std::iota(mine.begin(), mine.end(), 1000 * r);
  std::vector<std::size_t> counts;
  const auto all = comm.allgatherv(std::span<const int>(mine), &counts);
  ASSERT_EQ(all.size(), std::size_t(p) * (p - 1) / 2);
  ASSERT_EQ(counts.size(), std::size_t(p));
  std::size_t k = 0;
  for (int i = 0; i < p; ++i) {
    EXPECT_EQ(counts[i], std::size_t(i));
    for (int j = 0; j < i; ++j) EXPECT_EQ(all[k++], 1000 * i + j);
  }
  const auto ga = comm.gatherv(std::span<const int>(mine), root);
  EXPECT_EQ(ga.size(), r == root ? all.size() : 0u);
  if (r == root) {
    EXPECT_EQ(ga, all);
  }
  const auto ag = comm.allgather(r);
  ASSERT_EQ(ag.size(), std::size_t(p));
  for (int i = 0; i < p; ++i) EXPECT_EQ(ag[i], i);
}

template <class C>
void check_alltoall(const C& comm) {
  const int r = comm.rank(), p = comm.size();
  std::vector<std::int64_t> blocks;
  for (int to = 0; to < p; ++to) {
    blocks.push_back(100 * r + to);
    blocks.push_back(-(100 * r + to));
  }
  const auto got = comm.alltoall(std::span<const std::int64_t>(blocks));
  ASSERT_EQ(got.size(), std::size_t(2 * p));
  for (int from = 0; from < p; ++from) {
    EXPECT_EQ(got[2 * from], 100 * from + r);
    EXPECT_EQ(got[2 * from + 1], -(100 * from + r));
  }
  // Variable counts: rank r sends (r + to) % 3 payloads to rank `to`.
  std::vector<Payload> send;
  std::vector<std::size_t> scounts(static_cast<std::size_t>(p));
  for (int to = 0; to < p; ++to) {
    scounts[to] = std::size_t((r + to) % 3);
    for (std::size_t k = 0; k < scounts[to]; ++k)
      send.push_back({std::int64_t(r) * 1000 + to, double(k), {float(r), float(to), 0}});
  }
  comm.reset_stats();
  std::vector<std::size_t> rcounts;
  const auto recv = comm.alltoallv(std::span<const Payload>(send),
                                   std::span<const std::size_t>(scounts), &rcounts);
  std::size_t off = 0;
  for (int from = 0; from < p; ++from) {
    ASSERT_EQ(rcounts[from], std::size_t((from + r) % 3));
    for (std::size_t k = 0; k < rcounts[from]; ++k, ++off) {
      EXPECT_EQ(recv[off].id, std::int64_t(from) * 1000 + r);
      EXPECT_EQ(recv[off].value, double(k));
    }
  }
  EXPECT_EQ(off, recv.size());
  // Bytes to other ranks: payloads plus one count per other rank.
  std::size_t expected = 0;
  for (int to = 0; to < p; ++to)
    if (to != r) expected += scounts[to] * sizeof(Payload) + sizeof(std::size_t);
  EXPECT_EQ(comm.stats().bytes_sent, expected);
}

template <class C>
void check_split(const C& comm) {
  const int r = comm.rank(), p = comm.size();
  // Even and odd ranks, reversed order inside each group.
  const auto sub = comm.split(r % 2, -r);
  const int group_size = (p + 1 - r % 2) / 2;
  EXPECT_EQ(sub.size(), group_size);
  EXPECT_EQ(sub.sum(1), group_size);
  EXPECT_EQ(sub.max(r), r % 2 == 0 ? 2 * (group_size - 1) : 2 * group_size - 1);
  // Highest world rank of the group comes first.
  EXPECT_EQ(sub.min_loc(-r).rank, 0);
  EXPECT_EQ(comm.sum(1), p);  // the parent still works
}

}  // namespace pik_test
