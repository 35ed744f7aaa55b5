// The serial communication backend (one rank), usable in every build without
// mpirun, and the rank-grid choice.
#include <gtest/gtest.h>

#include <pik/comm/Environment.hpp>
#include <pik/domain/ProcessGrid.hpp>

#include "comm_checks.hpp"

namespace {
pik::SerialComm serial() { return pik::BasicEnvironment<pik::comm::SerialBackend>().world(); }
}  // namespace

TEST(SerialComm, IsOneRank) {
  const auto c = serial();
  EXPECT_EQ(c.rank(), 0);
  EXPECT_EQ(c.size(), 1);
  EXPECT_TRUE(c.is_root());
  EXPECT_STREQ(pik::SerialComm::backend_name(), "serial");
}
TEST(SerialComm, Reductions) { pik_test::check_reductions(serial()); }
TEST(SerialComm, BroadcastAndGather) { pik_test::check_broadcast_gather(serial()); }
TEST(SerialComm, AllToAll) { pik_test::check_alltoall(serial()); }
TEST(SerialComm, Split) { pik_test::check_split(serial()); }

TEST(SerialCommDeath, AbortPrintsWhyAndExitsNonZero) {
  EXPECT_EXIT(serial().abort("the reason", 3), ::testing::ExitedWithCode(3),
              "pik: rank 0/1: error: the reason");
  EXPECT_EXIT(serial().alltoallv(std::span<const int>(), std::span<const std::size_t>()),
              ::testing::ExitedWithCode(1), "send_counts must have one entry per rank");
  EXPECT_EXIT(serial().split(-1, 0), ::testing::ExitedWithCode(1), "color must be non-negative");
}

TEST(ProcessGrid, ClosestToCube) {
  using G3 = std::array<int, 3>;
  EXPECT_EQ(pik::choose_process_grid<3>(1), (G3{1, 1, 1}));
  EXPECT_EQ(pik::choose_process_grid<3>(2), (G3{2, 1, 1}));
  EXPECT_EQ(pik::choose_process_grid<3>(3), (G3{3, 1, 1}));
  EXPECT_EQ(pik::choose_process_grid<3>(4), (G3{2, 2, 1}));
  EXPECT_EQ(pik::choose_process_grid<3>(8), (G3{2, 2, 2}));
  EXPECT_EQ(pik::choose_process_grid<3>(12), (G3{3, 2, 2}));
  EXPECT_EQ(pik::choose_process_grid<3>(7), (G3{7, 1, 1}));
  EXPECT_EQ(pik::choose_process_grid<3>(1000), (G3{10, 10, 10}));
  EXPECT_EQ(pik::choose_process_grid<3>(10000), (G3{25, 20, 20}));
  EXPECT_EQ(pik::choose_process_grid<2>(6), (std::array<int, 2>{3, 2}));
}
