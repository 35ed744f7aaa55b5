// GoogleTest main for tests that run on every rank under mpirun: rank 0 prints the
// usual report, the other ranks print only their failures (tagged with the rank),
// and the exit status is non-zero on every rank if any rank failed.
#include <gtest/gtest.h>

#include <cstdio>

#include <pik/comm/Environment.hpp>

namespace {

class RankFailurePrinter : public ::testing::EmptyTestEventListener {
 public:
  explicit RankFailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (!r.failed()) return;
    std::fprintf(stderr, "[rank %d] %s:%d: failure\n%s\n", rank_,
                 r.file_name() ? r.file_name() : "?", r.line_number(), r.summary());
  }

 private:
  int rank_;
};

}  // namespace

int main(int argc, char** argv) {
  pik::Environment env(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  const pik::Comm comm = env.world();
  if (!comm.is_root()) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new RankFailurePrinter(comm.rank()));
  }
  const int failed = RUN_ALL_TESTS() != 0 ? 1 : 0;
  return comm.max(failed);
}
