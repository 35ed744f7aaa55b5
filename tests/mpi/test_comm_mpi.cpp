// pik::Comm under mpirun at any rank count (the serial backend when built without MPI).
#include <gtest/gtest.h>

#include "comm_checks.hpp"

namespace {
pik::Comm world() { return pik::Comm::world(); }
}  // namespace

TEST(Comm, Reductions) { pik_test::check_reductions(world()); }
TEST(Comm, BroadcastAndGather) { pik_test::check_broadcast_gather(world()); }
TEST(Comm, AllToAll) { pik_test::check_alltoall(world()); }
TEST(Comm, Split) { pik_test::check_split(world()); }

TEST(Comm, CopiesShareTheCommunicatorAndStatistics) {
  const auto a = world();
  const auto b = a;
  a.reset_stats();
  EXPECT_EQ(b.sum(2), 2 * a.size());
  EXPECT_EQ(a.stats().collectives, 1u);
  EXPECT_STREQ(pik::Comm::backend_name(), PIK_TEST_EXPECTED_BACKEND);
}
