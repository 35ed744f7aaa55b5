// ewald_ref: Ewald reference accelerations (pik::pm::ewald_accelerations) at a random
// sample of a periodic particle set, and the rms relative error of another code's
// accelerations of the same set (docs/cosmo.md, the comparison with FDPS).
//
//   ewald_ref --dump PREFIX | --ic FILE  [--sample 1000] [--seed 1] [--eps E] [--s 4]
//             [--out-pos FILE] [--out-ref FILE]
//
// --dump PREFIX reads PREFIX.0, PREFIX.1, ... (one file per rank, until one is
// missing), each int64 n then n records of 11 doubles: id, x, y, z, m, the
// short-range acceleration (3) and the long-range one (3), positions in box units
// [0, 1), G = 1; the sum of the two accelerations is compared with Ewald. --ic FILE
// reads a positions file instead (int64 n, n records x, y, z, m; what bench_cosmo
// --ic reads), with no accelerations to compare. --out-pos writes the set (ordered
// by id) as a positions file, --out-ref the sample: int64 count, then per particle
// int64 id and 3 doubles of Ewald acceleration (what bench_cosmo --ewald reads).
// --eps softens the nearest image with Plummer's law (pik::pm::EwaldParams).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <pik/io/CommandLine.hpp>
#include <pik/pik.hpp>
#include <pik/pm/Ewald.hpp>

using V = pik::Vec3<double>;

int main(int argc, char** argv) {
  pik::io::CommandLine cli("ewald_ref", "Ewald reference accelerations at a random sample of a periodic set, and another code's error.");
  cli.option("--dump", "", "per-rank dump files PREFIX.0, PREFIX.1, ... (id, x, y, z, m, a_short, a_long)", "PREFIX");
  cli.option("--ic", "", "positions file (int64 n; n x {x, y, z, m}), instead of --dump", "FILE");
  cli.option("--sample", "1000", "particles in the random sample", "N");
  cli.option("--seed", "1", "seed of the sample", "S");
  cli.option("--eps", "0", "Plummer softening of the nearest image, box units", "E");
  cli.option("--s", "4", "Ewald accuracy parameter (alpha r_c = s, k_max = 2 s alpha)", "S");
  cli.option("--out-pos", "", "write the set as a positions file", "FILE");
  cli.option("--out-ref", "", "write the sample's Ewald accelerations", "FILE");
  cli.parse(argc, argv);
  pik::Environment env(argc, argv);
  if (cli.given("--dump") == cli.given("--ic")) cli.fail("give exactly one of --dump and --ic");

  std::vector<V> pos, acc;
  std::vector<double> mass;
  if (cli.given("--dump")) {
    struct Rec {
      double id, x, y, z, m, a[3], ap[3];
    };
    std::vector<Rec> all;
    for (int r = 0;; ++r) {
      const std::string path = cli.str("--dump") + "." + std::to_string(r);
      std::ifstream f(path, std::ios::binary);
      if (!f) {
        if (r == 0) cli.fail("cannot open " + path);
        break;
      }
      std::int64_t n = 0;
      f.read(reinterpret_cast<char*>(&n), 8);
      if (!f || n < 0) cli.fail(path + ": bad count");
      const std::size_t at = all.size();
      all.resize(at + std::size_t(n));
      f.read(reinterpret_cast<char*>(all.data() + at), std::streamsize(sizeof(Rec) * std::size_t(n)));
      if (!f) cli.fail(path + " is short");
    }
    const std::size_t n = all.size();
    pos.resize(n), acc.resize(n), mass.resize(n);
    std::vector<char> seen(n, 0);
    for (const Rec& q : all) {
      const double idd = q.id;
      if (!(idd >= 0 && idd < double(n)) || seen[std::size_t(idd)]) cli.fail("dump: ids are not a permutation of 0..n-1");
      const std::size_t i = std::size_t(idd);
      seen[i] = 1;
      pos[i] = {q.x, q.y, q.z}, mass[i] = q.m, acc[i] = V{q.a[0], q.a[1], q.a[2]} + V{q.ap[0], q.ap[1], q.ap[2]};
    }
  } else {
    std::ifstream f(cli.str("--ic"), std::ios::binary);
    if (!f) cli.fail("cannot open " + cli.str("--ic"));
    std::int64_t n = 0;
    f.read(reinterpret_cast<char*>(&n), 8);
    if (!f || n <= 0) cli.fail(cli.str("--ic") + ": bad count");
    pos.resize(std::size_t(n)), mass.resize(std::size_t(n));
    for (std::size_t i = 0; i < pos.size(); ++i) {
      double r[4];
      f.read(reinterpret_cast<char*>(r), sizeof r);
      if (!f) cli.fail(cli.str("--ic") + " is short");
      pos[i] = {r[0], r[1], r[2]}, mass[i] = r[3];
    }
  }
  for (auto& x : pos)
    for (int d = 0; d < 3; ++d) {
      if (!(x[d] >= -1e-12 && x[d] <= 1 + 1e-12)) cli.fail("a coordinate lies outside the unit box");
      x[d] = std::clamp(x[d], 0.0, std::nextafter(1.0, 0.0));
    }
  const std::size_t n = pos.size();
  if (cli.given("--out-pos")) {
    std::ofstream f(cli.str("--out-pos"), std::ios::binary);
    const std::int64_t nn = std::int64_t(n);
    f.write(reinterpret_cast<const char*>(&nn), 8);
    for (std::size_t i = 0; i < n; ++i) {
      const double r[4] = {pos[i].x, pos[i].y, pos[i].z, mass[i]};
      f.write(reinterpret_cast<const char*>(r), sizeof r);
    }
    if (!f) cli.fail("cannot write " + cli.str("--out-pos"));
  }
  const std::size_t ns = std::min<std::size_t>(n, cli.count("--sample"));
  std::vector<std::size_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = i;
  std::mt19937_64 rng(cli.count("--seed"));
  for (std::size_t i = 0; i < ns; ++i) std::swap(ids[i], ids[i + std::uniform_int_distribution<std::size_t>(0, n - 1 - i)(rng)]);
  ids.resize(ns);
  std::sort(ids.begin(), ids.end());

  const double t0 = pik::wall_time();
  const auto ref = pik::pm::ewald_accelerations(pos, mass, ids, 1.0, {.s = cli.real("--s"), .eps = cli.real("--eps")});
  std::printf("ewald_ref: %zu particles, sample %zu, eps %g, s %g: %.1f s (%d threads)\n", n, ns, cli.real("--eps"),
              cli.real("--s"), pik::wall_time() - t0, pik::detail::max_threads());
  if (cli.given("--out-ref")) {
    std::ofstream f(cli.str("--out-ref"), std::ios::binary);
    const std::int64_t nn = std::int64_t(ns);
    f.write(reinterpret_cast<const char*>(&nn), 8);
    for (std::size_t t = 0; t < ns; ++t) {
      const std::int64_t id = std::int64_t(ids[t]);
      f.write(reinterpret_cast<const char*>(&id), 8);
      f.write(reinterpret_cast<const char*>(&ref[t]), 24);
    }
    if (!f) cli.fail("cannot write " + cli.str("--out-ref"));
  }
  if (!acc.empty()) {
    std::vector<double> e(ns);
    double s = 0;
    for (std::size_t t = 0; t < ns; ++t) {
      e[t] = pik::norm(acc[ids[t]] - ref[t]) / pik::norm(ref[t]);
      s += e[t] * e[t];
    }
    std::sort(e.begin(), e.end());
    std::printf("dump accelerations against Ewald: rms relative error %.3e, median %.3e, 90 %% %.3e, max %.3e\n",
                std::sqrt(s / double(ns)), e[ns / 2], e[ns * 9 / 10], e.back());
  }
  return 0;
}
