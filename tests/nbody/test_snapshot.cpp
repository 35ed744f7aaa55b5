// Snapshot formats: exact round trips, per-rank parts, and refusal of truncated,
// corrupted and foreign files with a message that names the file and the problem.
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <pik/io/SnapshotIo.hpp>

#include "TempDir.hpp"

using pik::io::Format;
using pik::io::IoError;
using pik::io::Snapshot;

namespace {

// Random particles plus values that text formats get wrong: -0, denormals, extremes.
Snapshot make_snapshot(std::size_t n, bool extras, unsigned seed = 7) {
  Snapshot s;
  s.time = 1.0 / 3.0;
  s.step = 12345;
  if (extras) {
    s.column("Acceleration", 3);
    s.column("Potential", 1);
  }
  s.resize(n);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double specials[] = {-0.0, 5e-324, 1.7976931348623157e308, -2.2250738585072014e-308,
                             1.0 / 3.0};
  for (std::size_t i = 0; i < n; ++i) {
    s.id[i] = (std::uint64_t(1) << 63) + i * 977;
    s.mass[i] = 1.0 / double(n) * (1 + u(rng));
    s.pos[i] = {u(rng), u(rng) * 1e30, u(rng) * 1e-30};
    s.vel[i] = {u(rng), specials[i % 5], u(rng)};
  }
  if (extras) {
    for (auto& c : s.extra)
      for (auto& v : c.data) v = u(rng);
  }
  s.attr.set("theta", 0.5);
  s.attr.set("dt", 1.0 / 256);
  s.attr.set("eps", std::sqrt(2.0) / 64);
  s.attr.set("ic", "plummer");
  s.attr.set("n", std::uint64_t(n));
  s.attr.set("note", "two words, and = signs");
  return s;
}

std::vector<char> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void dump(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::vector<Format> formats() {
  std::vector<Format> f = {Format::ascii, Format::binary};
  if (pik::io::have_hdf5) f.push_back(Format::hdf5);
  return f;
}

// Reading `path` fails with an error that starts with `where` (default: the path)
// and contains `what`.
void expect_refused(const std::string& path, const std::string& what, std::string where = "") {
  if (where.empty()) where = path;
  try {
    pik::io::read_snapshot(path);
    ADD_FAILURE() << path << ": read succeeded, expected an error containing '" << what << "'";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos)
        << "expected '" << what << "' in: " << e.what();
  }
}

class SnapshotFormat : public testing::TestWithParam<Format> {};

}  // namespace

TEST_P(SnapshotFormat, RoundTripIsExact) {
  pik_test::TempDir dir;
  for (std::size_t n : {0u, 1u, 5u, 1000u}) {
    for (bool extras : {false, true}) {
      const Snapshot s = make_snapshot(n, extras);
      const std::string path = dir.file("snap" + std::string(pik::io::extension(GetParam())));
      pik::io::write_snapshot(path, s, GetParam());
      EXPECT_EQ(pik::io::detect_format(path), GetParam());
      const Snapshot r = pik::io::read_snapshot(path);
      EXPECT_TRUE(pik::io::same_bits(s, r)) << "n=" << n << " extras=" << extras;
      ASSERT_EQ(r.size(), n);
      EXPECT_EQ(r.attr.get_double("eps"), std::sqrt(2.0) / 64);
      EXPECT_EQ(r.attr.get_string("note"), "two words, and = signs");
    }
  }
  // Nothing but the snapshot itself is left in the directory.
  EXPECT_EQ(dir.entries().size(), 1u);
}

TEST_P(SnapshotFormat, TruncatedFileIsRefused) {
  pik_test::TempDir dir;
  const std::string path = dir.file("snap");
  pik::io::write_snapshot(path, make_snapshot(300, true), GetParam());
  const std::vector<char> full = slurp(path);
  // Cut points from one byte to almost everything; ASCII may lose its final newline
  // and still be complete, so it is cut at least 3 bytes short.
  const std::size_t keep_max = full.size() - (GetParam() == Format::ascii ? 3 : 1);
  for (std::size_t keep : {std::size_t(0), std::size_t(1), std::size_t(20), std::size_t(100),
                           full.size() / 3, full.size() / 2, keep_max}) {
    const std::string cut = dir.file("cut" + std::to_string(keep));
    dump(cut, std::vector<char>(full.begin(), full.begin() + std::ptrdiff_t(keep)));
    EXPECT_THROW(pik::io::read_snapshot(cut), IoError) << "kept " << keep << " of " << full.size();
  }
}

TEST_P(SnapshotFormat, CorruptedDataAreRefused) {
  pik_test::TempDir dir;
  const std::string path = dir.file("snap");
  pik::io::write_snapshot(path, make_snapshot(2000, false), GetParam());
  std::vector<char> bytes = slurp(path);
  if (GetParam() == Format::ascii) {
    // Text has no checksum; a damaged number is still refused with its line.
    const auto at = std::string(bytes.begin(), bytes.end()).find("\n", bytes.size() / 2) + 3;
    bytes[at] = 'x';
    dump(path, bytes);
    expect_refused(path, "is not a");
  } else {
    // Flip one bit in the middle of the particle data.
    bytes[bytes.size() / 2 + 3] ^= 0x10;
    dump(path, bytes);
    expect_refused(path, GetParam() == Format::binary ? "checksum mismatch" : "corrupt");
  }
}

INSTANTIATE_TEST_SUITE_P(AllFormats, SnapshotFormat, testing::ValuesIn(formats()),
                         [](const auto& info) { return pik::io::format_name(info.param); });

TEST(BinarySnapshot, EveryRegionIsChecked) {
  pik_test::TempDir dir;
  const std::string path = dir.file("snap.pbin");
  pik::io::write_binary(path, make_snapshot(100, true));
  const std::vector<char> good = slurp(path);
  auto flip = [&](std::size_t at, const std::string& what) {
    std::vector<char> bad = good;
    bad[at] ^= 0x01;
    dump(path, bad);
    expect_refused(path, what);
  };
  flip(0, "not a pik snapshot");
  flip(8, "corrupt header");             // version
  flip(16, "corrupt header");            // particle count
  flip(128 + 5, "corrupt field table");  // first field's name
  // Attributes follow the field table: 4 core fields + 2 extra columns.
  flip(128 + 6 * 64 + 2, "corrupt attributes");
  flip(good.size() - 3, "corrupt end marker");
  flip(good.size() - 20, "field 'Potential' is corrupt");

  std::vector<char> longer = good;
  longer.push_back('\0');
  dump(path, longer);
  expect_refused(path, "unexpected bytes after the end");

  dump(path, std::vector<char>(good.begin(), good.end() - 8));
  expect_refused(path, "truncated");

  expect_refused(dir.file("missing.pbin"), "cannot open");
}

TEST(Snapshot, DirectoryAndMissingOutputAreNamed) {
  pik_test::TempDir dir;
  // A directory is not "an empty file" (fopen succeeds on it; fread fails).
  const std::string sub = dir.file("run");
  std::filesystem::create_directory(sub);
  expect_refused(sub, "is a directory");
  // A missing output names the path the user gave, not only its part-0 file.
  const std::string missing = dir.file("nothing.pbin");
  try {
    pik::io::read_snapshot_parts(missing);
    ADD_FAILURE() << "read_snapshot_parts(" << missing << ") succeeded";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(missing + ": cannot open", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("nothing.0.pbin"), std::string::npos) << e.what();
  }
}

TEST(AsciiSnapshot, ErrorsNameTheLine) {
  pik_test::TempDir dir;
  const std::string path = dir.file("snap.txt");
  pik::io::write_ascii(path, make_snapshot(3, false));
  std::string text;
  {
    auto b = slurp(path);
    text.assign(b.begin(), b.end());
  }
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos);
    t.replace(at, from.size(), to);
    dump(path, std::vector<char>(t.begin(), t.end()));
  };
  with("# end\n", "");
  expect_refused(path, "truncated: expected '# end'", path + ":");
  with("# pik ascii snapshot 1", "# something else");
  expect_refused(path, "not a pik ASCII snapshot", path + ":1:");
  // Drop the last column of the first particle line.
  {
    std::string t = text;
    const auto row = t.find('\n', t.find("# columns")) + 1;
    const auto sp = t.rfind(' ', t.find('\n', row));
    t.erase(sp, t.find('\n', row) - sp);
    dump(path, std::vector<char>(t.begin(), t.end()));
    expect_refused(path, "expected 8 columns, found 7", path + ":");
  }
  dump(path, {});
  expect_refused(path, "empty file");
}

TEST(Snapshot, PartsAreWrittenPerRankAndGathered) {
  EXPECT_EQ(pik::io::part_path("out/snap_0003.pbin", 2, 4), "out/snap_0003.2.pbin");
  EXPECT_EQ(pik::io::part_path("out/snap_0003.pbin", 0, 1), "out/snap_0003.pbin");
  EXPECT_EQ(pik::io::part_path("out.d/snap", 1, 2), "out.d/snap.1");
  EXPECT_EQ(pik::io::part_path(".hidden", 1, 2), ".hidden.1");

  pik_test::TempDir dir;
  for (Format f : formats()) {
    const Snapshot whole = make_snapshot(1000, true);
    const std::string base = dir.file(std::string("parts") + pik::io::extension(f));
    const std::size_t cuts[4] = {0, 400, 400, 1000};  // part 1 is empty, as a rank may be
    for (std::uint32_t p = 0; p < 3; ++p) {
      Snapshot part = whole;
      part.part = p;
      part.n_parts = 3;
      part.n_total = whole.size();
      part.first_index = cuts[p];
      auto slice = [&](auto& v, std::size_t k) {
        using V = std::decay_t<decltype(v)>;
        v = V(v.begin() + std::ptrdiff_t(cuts[p] * k), v.begin() + std::ptrdiff_t(cuts[p + 1] * k));
      };
      slice(part.id, 1), slice(part.mass, 1), slice(part.pos, 1), slice(part.vel, 1);
      for (auto& c : part.extra) slice(c.data, std::size_t(c.components));
      pik::io::write_snapshot_part(base, part, f);
    }
    Snapshot merged = pik::io::read_snapshot_parts(base);
    Snapshot expect = whole;
    expect.n_total = whole.size();
    EXPECT_TRUE(pik::io::same_bits(merged, expect)) << pik::io::format_name(f);

    // A missing part is reported by name.
    std::filesystem::remove(pik::io::part_path(base, 2, 3));
    try {
      pik::io::read_snapshot_parts(base);
      ADD_FAILURE() << "missing part accepted";
    } catch (const IoError& e) {
      EXPECT_EQ(e.path(), pik::io::part_path(base, 2, 3));
    }
  }
}

TEST(Snapshot, InconsistentSnapshotIsNotWritten) {
  pik_test::TempDir dir;
  Snapshot s = make_snapshot(10, true);
  s.pos.pop_back();
  EXPECT_THROW(pik::io::write_binary(dir.file("a"), s), IoError);
  s = make_snapshot(10, true);
  s.extra[1].data.push_back(1.0);
  EXPECT_THROW(pik::io::write_ascii(dir.file("a"), s), IoError);
  EXPECT_TRUE(dir.entries().empty());
}

TEST(Snapshot, FormatNames) {
  EXPECT_EQ(pik::io::format_from_name("binary"), Format::binary);
  EXPECT_EQ(pik::io::format_from_name("ascii"), Format::ascii);
  EXPECT_THROW(pik::io::format_from_name("gadget2"), std::invalid_argument);
  if (pik::io::have_hdf5)
    EXPECT_EQ(pik::io::format_from_name("hdf5"), Format::hdf5);
  else
    EXPECT_THROW(pik::io::format_from_name("hdf5"), std::invalid_argument);
}

TEST(Attributes, TypedValuesRoundTrip) {
  pik::io::Attributes a;
  a.set("x", 0.1);
  a.set("big", std::uint64_t(18446744073709551615ull));
  a.set("neg", std::int64_t(-5));
  a.set("flag", true);
  EXPECT_EQ(a.get_double("x"), 0.1);
  EXPECT_EQ(a.get_int("neg"), -5);
  EXPECT_TRUE(a.get_bool("flag"));
  EXPECT_EQ(a.get_string("big"), "18446744073709551615");
  EXPECT_THROW(a.get_double("missing"), IoError);
  EXPECT_THROW(a.get_int("x"), IoError);
  EXPECT_THROW(a.set("bad\tkey", 1.0), IoError);
  EXPECT_THROW(a.set("k", "two\nlines"), IoError);
}
