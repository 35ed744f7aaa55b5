// The shared SPH layer against exact answers: kernel normalisation, the
// smoothing-length root on a lattice, step limits, and the driver's restart.
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <pik/pik.hpp>
#include <pik/sph/Driver.hpp>
#include <pik/sph/Smoothing.hpp>
#include <pik/sph/SmoothingLength.hpp>
#include <pik/sph/TimeStep.hpp>

using pik::sph::Shape;

// The integral of W over the plane (2D) and space (3D) is 1 for every shape, by the
// midpoint rule in r (W is smooth inside its support).
TEST(Smoothing, Normalised) {
  for (int dim : {2, 3})
    for (Shape s : {Shape::cubic, Shape::wendland2, Shape::wendland4}) {
      const int n = 20000;
      double sum = 0;
      for (int i = 0; i < n; ++i) {
        const double r = (i + 0.5) / n;
        sum += pik::sph::kernel_w(r, 1.0, dim, s) * (dim == 3 ? 4 * M_PI * r * r : 2 * M_PI * r) / n;
      }
      EXPECT_NEAR(sum, 1.0, 1e-6) << "dim " << dim << " " << pik::sph::shape_name(s);
      EXPECT_EQ(pik::sph::kernel_w(1.0, 1.0, dim, s), 0.0);
    }
  EXPECT_EQ(pik::sph::shape_from_name("wendland2"), Shape::wendland2);
  EXPECT_THROW(pik::sph::shape_from_name("gauss"), pik::Error);
}

TEST(StepLimits, SmallestWinsAndIsNamed) {
  pik::sph::StepLimits lim;
  EXPECT_EQ(lim.limiter(), "none");
  lim.add("courant", 0.3);
  lim.add("viscosity", 0.1);
  lim.add("courant", 0.05);
  EXPECT_DOUBLE_EQ(lim.dt(), 0.05);
  EXPECT_EQ(lim.limiter(), "courant");
  EXPECT_EQ(lim.all().size(), 2u);
  EXPECT_DOUBLE_EQ(pik::sph::diffusion(0.1, 2.0, 0.25), 0.25 * 0.01 / 2.0);
  EXPECT_DOUBLE_EQ(pik::sph::courant(0.1, 2.0, 0.3), 0.015);
}

namespace {
struct Gas {
  std::uint32_t id = 0;
  double mass = 0, h = 0, rho = 0, drhodh = 0, h_lo = 0, h_hi = 0;
  pik::Vec3<double> pos{}, vel{}, vel_half{}, acc{};
  double u = 0, u_half = 0, dudt = 0;
  const pik::Vec3<double>& getPos() const { return pos; }
  void setPos(const pik::Vec3<double>& p) { pos = p; }
};

// Brute-force periodic density of a unit 2D lattice (spacing 1/n) and its h-derivative.
void density_pass(std::vector<Gas>& ps, int n) {
  for (auto& p : ps) {
    auto rho_at = [&](double h) {
      double r = 0;
      for (const auto& q : ps)
        for (int sx = -1; sx <= 1; ++sx)
          for (int sy = -1; sy <= 1; ++sy) {
            const double dx = p.pos.x - q.pos.x + sx, dy = p.pos.y - q.pos.y + sy;
            r += q.mass * pik::sph::kernel_w(std::sqrt(dx * dx + dy * dy), h, 2, Shape::cubic);
          }
      return r;
    };
    p.rho = rho_at(p.h);
    const double e = 1e-6 * p.h;
    p.drhodh = (rho_at(p.h + e) - rho_at(p.h - e)) / (2 * e);
  }
  (void)n;
}
// A unit 2D lattice of n x n particles of mass 1/n^2, h = 0.7/n (far from the root).
std::vector<Gas> unit_lattice(int n) {
  std::vector<Gas> ps;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      Gas g;
      g.id = std::uint32_t(ps.size()), g.mass = 1.0 / (n * n), g.h = 0.7 / n;
      g.pos = {(i + 0.5) / n, (j + 0.5) / n, 0};
      ps.push_back(g);
    }
  return ps;
}
}  // namespace

// On a uniform lattice every h converges to the same root of pi h^2 rho / m = N_ngb, and
// the density is the lattice's (1) within the kernel's discretisation error.
TEST(SmoothingLength, ConvergesOnALattice) {
  const int n = 12;
  std::vector<Gas> ps = unit_lattice(n);
  pik::sph::SmoothingLengthParams prm{.nngb = 20, .tol = 1e-4};
  const int passes = pik::sph::iterate_smoothing_length<2>(ps, [&] { density_pass(ps, n); }, prm);
  EXPECT_GT(passes, 2);
  EXPECT_LT(passes, 20);
  for (const auto& p : ps) {
    EXPECT_NEAR(M_PI * p.h * p.h * p.rho / p.mass, 20.0, 20 * 1e-4);
    EXPECT_NEAR(p.rho, 1.0, 0.02);
    EXPECT_NEAR(p.h, ps[0].h, 1e-9);
  }
  prm.max_passes = 1;
  for (auto& p : ps) p.h = 0.3 / n;
  EXPECT_THROW(pik::sph::iterate_smoothing_length<2>(ps, [&] { density_pass(ps, n); }, prm), pik::Error);
}

// The cap (SmoothingLengthParams::h_max): above the root it changes nothing; below it every
// particle stops at the cap, counted as converged, with the density of h = h_max; a negative
// cap is refused.
TEST(SmoothingLength, CapHMax) {
  const int n = 12;
  std::vector<Gas> ps = unit_lattice(n);
  const auto start = ps;
  pik::sph::SmoothingLengthParams prm{.nngb = 20, .tol = 1e-4};
  pik::sph::iterate_smoothing_length<2>(ps, [&] { density_pass(ps, n); }, prm);
  const double root = ps[0].h;

  auto capped = start;
  prm.h_max = 1.5 * root;
  pik::sph::iterate_smoothing_length<2>(capped, [&] { density_pass(capped, n); }, prm);
  for (std::size_t i = 0; i < ps.size(); ++i) EXPECT_NEAR(capped[i].h, root, 1e-9);

  capped = start;
  for (auto& p : capped) p.h = 2 * root;  // above the cap at the start: lowered to it
  prm.h_max = 0.8 * root;
  const int passes = pik::sph::iterate_smoothing_length<2>(capped, [&] { density_pass(capped, n); }, prm);
  EXPECT_LT(passes, 20);
  auto at_cap = start;
  for (auto& p : at_cap) p.h = prm.h_max;
  density_pass(at_cap, n);
  for (std::size_t i = 0; i < capped.size(); ++i) {
    EXPECT_DOUBLE_EQ(capped[i].h, prm.h_max);
    EXPECT_NEAR(capped[i].rho, at_cap[i].rho, 1e-12 * at_cap[i].rho);
    EXPECT_LT(M_PI * capped[i].h * capped[i].h * capped[i].rho / capped[i].mass, 20.0 * (1 - 1e-4));
  }
  prm.h_max = -1;
  EXPECT_THROW(pik::sph::iterate_smoothing_length<2>(capped, [&] { density_pass(capped, n); }, prm), pik::Error);
}

namespace {
// A minimal model for the driver: independent harmonic oscillators (a = -x, du/dt = -u),
// step limit 0.05 / (1 + |x|). The exact energy of each oscillator is conserved to O(dt^2).
struct Oscillators {
  pik::ParticleSystem<Gas> ps;
  long computes = 0;
  pik::ParticleSystem<Gas>& particles() { return ps; }
  const pik::ParticleSystem<Gas>& particles() const { return ps; }
  void compute() {
    ++computes;
    for (auto& p : ps) p.acc = p.pos * -1.0, p.dudt = -p.u;
  }
  pik::sph::StepLimits limits() const {
    pik::sph::StepLimits l;
    for (const auto& p : ps) l.add("oscillator", 0.05 / (1 + pik::norm(p.pos)));
    return l;
  }
  std::vector<std::string> diagnostic_names() const { return {"E", "U"}; }
  std::vector<double> diagnostics() const {
    double e = 0, u = 0;
    for (const auto& p : ps) e += 0.5 * (pik::norm2(p.vel) + pik::norm2(p.pos)), u += p.u;
    return {e, u};
  }
  void fill_snapshot(pik::io::Snapshot& s, bool checkpoint) const {
    auto& u = s.column("InternalEnergy", 1);
    for (std::size_t i = 0; i < ps.size(); ++i) u.data[i] = ps[i].u;
    if (checkpoint) {
      auto& a = s.column("Acceleration", 3);
      for (std::size_t i = 0; i < ps.size(); ++i)
        a.data[3 * i] = ps[i].acc.x, a.data[3 * i + 1] = ps[i].acc.y, a.data[3 * i + 2] = ps[i].acc.z;
      auto& d = s.column("DuDt", 1);
      for (std::size_t i = 0; i < ps.size(); ++i) d.data[i] = ps[i].dudt;
    }
  }
  void restore(const pik::io::Snapshot& s) {
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const auto& a = s.find("Acceleration")->data;
      ps[i].u = s.find("InternalEnergy")->data[i], ps[i].dudt = s.find("DuDt")->data[i];
      ps[i].acc = {a[3 * i], a[3 * i + 1], a[3 * i + 2]};
    }
  }
  static Oscillators make() {
    Oscillators o;
    for (int i = 0; i < 5; ++i) {
      Gas g;
      g.id = std::uint32_t(i), g.mass = 1, g.pos = {1.0 + i, 0.5 * i, 0}, g.u = 1;
      o.ps.add(g);
    }
    return o;
  }
};

std::string slurp(const std::string& f) {
  std::ifstream in(f, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

TEST(Driver, RunsToTheEndWithOutputsAndRestartsBitForBit) {
  const auto dir = std::filesystem::temp_directory_path() / "pik_test_sph_driver";
  std::filesystem::remove_all(dir);
  pik::sph::RunParams prm;
  prm.t_end = 2.0, prm.snapshots = 4, prm.out = (dir / "whole").string();
  auto a = Oscillators::make();
  pik::sph::Driver da(a, prm);
  da.run();
  EXPECT_DOUBLE_EQ(da.time(), 2.0);
  EXPECT_EQ(da.limiter(), "oscillator");
  for (int k = 0; k <= 4; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "snap_%04d.pbin", k);
    EXPECT_TRUE(std::filesystem::exists(dir / "whole" / name)) << name;
  }
  // Outputs land exactly on t_end k / 4.
  EXPECT_DOUBLE_EQ(pik::io::read_snapshot((dir / "whole" / "snap_0002.pbin").string()).time, 1.0);
  // Leapfrog: the oscillators' energy is conserved to O(dt^2), u decays as exp(-t).
  const auto d = a.diagnostics();
  double e0 = 0;
  for (int i = 0; i < 5; ++i) e0 += 0.5 * ((1.0 + i) * (1.0 + i) + 0.25 * i * i);
  EXPECT_NEAR(d[0] / e0, 1.0, 1e-3);
  EXPECT_NEAR(d[1] / 5, std::exp(-2.0), 1e-3);

  prm.out = (dir / "split").string();
  prm.max_steps = da.steps() / 2;
  auto b = Oscillators::make();
  pik::sph::Driver(b, prm).run();
  prm.max_steps = 0, prm.restart = (dir / "split" / "checkpoint.pbin").string();
  auto c = Oscillators::make();
  pik::sph::Driver dc(c, prm);
  dc.run();
  EXPECT_EQ(dc.steps(), da.steps());
  EXPECT_EQ(c.computes, da.steps() - da.steps() / 2);  // no force pass at the restart
  for (const char* f : {"snap_0004.pbin", "log.txt", "checkpoint.pbin"})
    EXPECT_EQ(slurp((dir / "whole" / f).string()), slurp((dir / "split" / f).string())) << f;

  // Restarting a finished run is refused; so is a bad end time.
  auto e = Oscillators::make();
  prm.restart = (dir / "whole" / "checkpoint.pbin").string();
  EXPECT_THROW(pik::sph::Driver(e, prm).run(), pik::Error);
  pik::sph::RunParams bad;
  bad.t_end = -1;
  EXPECT_THROW(pik::sph::Driver(e, bad), pik::Error);
  std::filesystem::remove_all(dir);
}

/// Step column of a log.txt (comment lines skipped).
std::vector<long> logged_steps(const std::string& path) {
  std::ifstream in(path);
  std::vector<long> steps;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') steps.push_back(std::stol(line));
  return steps;
}

// A log row every log_every steps, plus the rows of the outputs, checkpoints and the last
// step; the rows it writes are the every-step log's rows; a restart keeps the interval.
TEST(Driver, LogEveryKeepsTheRowsOfOutputsCheckpointsAndTheEnd) {
  const auto dir = std::filesystem::temp_directory_path() / "pik_test_sph_log_every";
  std::filesystem::remove_all(dir);
  pik::sph::RunParams prm;
  prm.t_end = 2.0, prm.snapshots = 4, prm.out = (dir / "every").string();
  auto a = Oscillators::make();
  pik::sph::Driver da(a, prm);
  da.run();
  const auto all = logged_steps((dir / "every" / "log.txt").string());
  ASSERT_EQ(long(all.size()), da.steps() + 1);  // step 0 and every step

  prm.out = (dir / "sparse").string(), prm.log_every = 7, prm.checkpoint_every = 10;
  auto b = Oscillators::make();
  pik::sph::Driver db(b, prm);
  db.run();
  const auto some = logged_steps((dir / "sparse" / "log.txt").string());
  ASSERT_EQ(db.steps(), da.steps());
  EXPECT_EQ(some.front(), 0);
  EXPECT_EQ(some.back(), db.steps());
  std::vector<long> outputs;  // the steps at which a snapshot was written: their rows are there
  for (int k = 1; k <= 4; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "snap_%04d.pbin", k);
    outputs.push_back(long(pik::io::read_snapshot((dir / "sparse" / name).string()).step));
  }
  for (long st = 1; st <= db.steps(); ++st) {
    const bool want = st % 7 == 0 || st % 10 == 0 || st == db.steps() ||
                      std::find(outputs.begin(), outputs.end(), st) != outputs.end();
    EXPECT_EQ(std::count(some.begin(), some.end(), st), want ? 1 : 0) << "step " << st;
  }
  EXPECT_LT(some.size(), all.size() / 3);
  // the same rows as the every-step log's, character for character
  std::ifstream fa((dir / "every" / "log.txt").string()), fb((dir / "sparse" / "log.txt").string());
  std::vector<std::string> ra, rb;
  for (std::string l; std::getline(fa, l);) ra.push_back(l);
  for (std::string l; std::getline(fb, l);) rb.push_back(l);
  for (const auto& r : rb) EXPECT_TRUE(std::find(ra.begin(), ra.end(), r) != ra.end()) << r;

  // split at a checkpoint and restarted: the same sparse log
  prm.out = (dir / "split").string(), prm.max_steps = 20;
  auto c = Oscillators::make();
  pik::sph::Driver(c, prm).run();
  prm.max_steps = 0, prm.restart = (dir / "split" / "checkpoint.pbin").string();
  auto d = Oscillators::make();
  pik::sph::Driver(d, prm).run();
  EXPECT_EQ(slurp((dir / "sparse" / "log.txt").string()), slurp((dir / "split" / "log.txt").string()));

  pik::sph::RunParams bad;
  bad.log_every = 0;
  EXPECT_THROW(pik::sph::Driver(d, bad), pik::Error);
  std::filesystem::remove_all(dir);
}
