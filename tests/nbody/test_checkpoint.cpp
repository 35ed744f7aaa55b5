// Checkpoints, the diagnostics log, and the random-engine state helpers.
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include <pik/io/Checkpoint.hpp>
#include <pik/io/DiagnosticsLog.hpp>
#include <pik/io/SnapshotIo.hpp>

#include "TempDir.hpp"

using pik::io::IoError;

TEST(Checkpoint, RoundTripAndKindCheck) {
  pik_test::TempDir dir;
  pik::io::Snapshot s;
  s.column("Acceleration", 3);
  s.resize(10);
  for (std::size_t i = 0; i < 10; ++i) {
    s.id[i] = 9 - i;
    s.pos[i] = {0.1 * double(i), 1.0 / 3.0, -1e-300};
    s.extra[0].data[3 * i] = 1.0 / double(i + 1);
  }
  s.time = 0.1 + 0.2;
  s.step = 77;
  s.attr.set("dt", 1.0 / 256);
  const std::string path = dir.file("run.chk");
  pik::io::write_checkpoint(path, s);
  const auto r = pik::io::read_checkpoint(path, {"Acceleration"}, {"dt"});
  EXPECT_EQ(r.attr.get_string("pik.kind"), "checkpoint");
  pik::io::Snapshot expect = s;
  expect.attr.set("pik.kind", "checkpoint");
  EXPECT_TRUE(pik::io::same_bits(r, expect));

  EXPECT_THROW(pik::io::read_checkpoint(path, {"Potential"}), IoError);
  EXPECT_THROW(pik::io::read_checkpoint(path, {}, {"theta"}), IoError);
  // A plain snapshot is not a checkpoint.
  pik::io::write_binary(dir.file("snap.pbin"), s);
  EXPECT_THROW(pik::io::read_checkpoint(dir.file("snap.pbin")), IoError);
  // Neither is a text file.
  pik::io::write_ascii(dir.file("snap.txt"), s);
  EXPECT_THROW(pik::io::read_checkpoint(dir.file("snap.txt")), IoError);
}

TEST(Checkpoint, EngineStateRestoresTheSequence) {
  std::mt19937_64 a(12345);
  for (int i = 0; i < 1000; ++i) a();
  const std::string state = pik::io::engine_state(a);
  std::mt19937_64 b;
  pik::io::restore_engine(b, state, "test");
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a(), b());
  EXPECT_THROW(pik::io::restore_engine(b, "garbage", "test"), IoError);
}

TEST(DiagnosticsLog, ResumeDropsRowsPastTheCheckpoint) {
  pik_test::TempDir dir;
  const std::string path = dir.file("energy.txt");
  {
    pik::io::DiagnosticsLog log(path, {"step", "time", "dE"});
    for (int s = 0; s <= 10; ++s) log.row({double(s), s * 0.1, 1e-7 * s});
  }
  {
    pik::io::DiagnosticsLog log(path, {"step", "time", "dE"}, 6);  // restart at step 6
    for (int s = 7; s <= 8; ++s) log.row({double(s), s * 0.1, 1e-7 * s});
    EXPECT_THROW(log.row({1.0}), IoError);
  }
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "# step time dE");
  std::vector<int> steps;
  for (std::string line; std::getline(in, line);) steps.push_back(std::stoi(line));
  EXPECT_EQ(steps, (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_THROW(pik::io::DiagnosticsLog(path, {"step", "other"}, 3), IoError);
  EXPECT_THROW(pik::io::DiagnosticsLog(path, {"time"}), IoError);
}
