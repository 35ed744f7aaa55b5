// The progress line: redrawn with '\r' on a terminal, plain lines otherwise.
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include <pik/io/Progress.hpp>

namespace {

std::string read_all(std::FILE* f) {
  std::rewind(f);
  std::string s;
  for (int c; (c = std::fgetc(f)) != EOF;) s += char(c);
  return s;
}

}  // namespace

TEST(Progress, FileGetsPlainLines) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    pik::io::Progress p(0, 100, f, /*log_interval_s=*/0.0);
    EXPECT_FALSE(p.interactive());
    for (int s = 1; s <= 100; ++s) p.update(s, s / 64.0, 1e-6, 2.5e8);
  }
  const std::string out = read_all(f);
  std::fclose(f);
  EXPECT_EQ(out.find('\r'), std::string::npos);
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 100);
  EXPECT_NE(out.find("step 100/100"), std::string::npos) << out;
  EXPECT_NE(out.find("|dE/E| 1.00e-06"), std::string::npos) << out;
  EXPECT_NE(out.find("2.5e+08 int/s"), std::string::npos) << out;
  EXPECT_NE(out.find("ETA 0:00"), std::string::npos) << out;
}

TEST(Progress, FileLinesAreThrottled) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  pik::io::Progress p(0, 1000, f, /*log_interval_s=*/3600.0);
  for (int s = 1; s <= 1000; ++s) p.update(s, s, NAN, 1.0);
  const std::string out = read_all(f);
  std::fclose(f);
  // The first step and the last, nothing in between within an hour.
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 2) << out;
}

TEST(Progress, TerminalLineIsRedrawnInPlace) {
  const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(::grantpt(master), 0);
  ASSERT_EQ(::unlockpt(master), 0);
  const int slave = ::open(::ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(slave, 0);
  std::FILE* tty = ::fdopen(slave, "w");
  ASSERT_NE(tty, nullptr);
  {
    pik::io::Progress p(10, 20, tty);  // a resumed run: steps 11..20
    EXPECT_TRUE(p.interactive());
    for (int s = 11; s <= 20; ++s) p.update(s, s * 0.5, 3e-5, 1e9);
  }
  std::fclose(tty);
  std::string out;
  char buf[4096];
  // The terminal turns "\n" into "\r\n"; read what is there without blocking.
  ::fcntl(master, F_SETFL, O_NONBLOCK);
  for (ssize_t k; (k = ::read(master, buf, sizeof buf)) > 0;) out.append(buf, std::size_t(k));
  ::close(master);
  EXPECT_NE(out.find("\rstep 11/20"), std::string::npos) << out;
  EXPECT_NE(out.find("step 20/20"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;  // only after the last
}

TEST(Progress, DurationFormat) {
  EXPECT_EQ(pik::io::format_duration(0.4), "0:00");
  EXPECT_EQ(pik::io::format_duration(65), "1:05");
  EXPECT_EQ(pik::io::format_duration(3725), "1:02:05");
  EXPECT_EQ(pik::io::format_duration(NAN), "--:--");
}
