// Long-range tree: forces against brute-force O(N^2) oracles, accuracy vs theta for
// monopole and quadrupole, thread-count independence, list reuse, imported particles.
#include <gtest/gtest.h>

#include <cstring>

#include "support.hpp"

namespace {

using pt::Accel;
using pt::Body;
using pt::Dist;

template <class T>
class LongRange : public ::testing::Test {};
using Reals = ::testing::Types<float, double>;
TYPED_TEST_SUITE(LongRange, Reals);

constexpr double eps2 = 1e-6;
// Softening well below the clumps' scale (1e-3): near the softening length the
// multipole expansion of the softened potential is not the point-mass one.
double eps2_for(Dist d) { return d == Dist::clustered ? 1e-12 : eps2; }

template <class T, class SPJ, class KS>
pt::ErrorStats run(pik::ParticleSystem<Body<T>>& ps, double theta, KS ks, double e2 = eps2, int leaf = 8,
                   int group = 32) {
  pik::LongRangeTree<Accel<T>, Body<T>, Body<T>, SPJ> tree({theta, leaf, group});
  tree.calcForceAllAndWriteBack(pt::Gravity<T>{T(e2)}, ks, ps);
  return pt::acc_error(ps, e2);
}

// theta = 0 opens every cell: the tree is a direct sum in another order.
TYPED_TEST(LongRange, ThetaZeroIsDirectSum) {
  using T = TypeParam;
  for (Dist d : {Dist::uniform, Dist::plummer, Dist::clustered}) {
    auto ps = pt::make<T>(d, 700);
    auto e = run<T, pik::SPJMonopole<T>>(ps, 0.0, pt::Gravity<T>{T(eps2_for(d))}, eps2_for(d));
    const double tol = std::is_same_v<T, float> ? 2e-4 : 1e-11;
    EXPECT_LT(e.max, tol) << pt::name(d);
  }
}

// Error against theta. Bounds hold with margin for these seeds; quadrupole must be
// clearly better than monopole at every theta.
TYPED_TEST(LongRange, ErrorVersusTheta) {
  using T = TypeParam;
  // Bounds on rms and max relative error (about 1.5x what these seeds give); the
  // quadrupole must also beat the monopole by a wide margin at the same theta.
  struct Row {
    double theta, rms_mono, max_mono, rms_quad;
  };
  const Row rows[] = {{0.3, 1.3e-3, 2e-2, 1.5e-4},
                      {0.5, 3.5e-3, 4e-2, 6e-4},
                      {0.7, 7e-3, 8e-2, 1.5e-3},
                      {1.0, 1.2e-2, 1.5e-1, 4e-3}};
  for (Dist d : {Dist::uniform, Dist::plummer, Dist::clustered}) {
    for (const Row& r : rows) {
      auto ps = pt::make<T>(d, 1500, 7);
      const double e2 = eps2_for(d);
      auto mono = run<T, pik::SPJMonopole<T>>(ps, r.theta, pt::Gravity<T>{T(e2)}, e2);
      auto quad = run<T, pik::SPJQuadrupole<T>>(ps, r.theta, pt::GravityQuad<T>{T(e2)}, e2);
      SCOPED_TRACE(std::string(pt::name(d)) + " theta=" + std::to_string(r.theta));
      EXPECT_LT(mono.rms, r.rms_mono);
      EXPECT_LT(mono.max, r.max_mono);
      EXPECT_LT(quad.rms, r.rms_quad);
      EXPECT_LT(quad.rms, 0.4 * mono.rms) << "mono " << mono.rms << " quad " << quad.rms;
      EXPECT_LT(quad.max, 0.5 * mono.max);
      std::printf("%-9s theta %.1f  monopole rms %.2e max %.2e  quadrupole rms %.2e max %.2e\n",
                  pt::name(d), r.theta, mono.rms, mono.max, quad.rms, quad.max);
    }
  }
}

// The three opening criteria at the same theta: the centre-of-mass tests open fewer
// cells than the box test; adding the centre-of-mass offset (d > s/theta + delta)
// opens every cell the plain centre-of-mass test opens, so it never has fewer
// interactions, and it must stay within its error bound.
TYPED_TEST(LongRange, OpeningCriteria) {
  using T = TypeParam;
  for (Dist d : {Dist::uniform, Dist::plummer, Dist::clustered}) {
    for (double theta : {0.5, 0.8}) {
      const double e2 = eps2_for(d);
      auto ps = pt::make<T>(d, 1500, 11);
      double rms[3];
      std::uint64_t n[3];
      const pik::Opening kinds[3] = {pik::Opening::box, pik::Opening::centre_of_mass,
                                     pik::Opening::centre_of_mass_offset};
      for (int k = 0; k < 3; ++k) {
        pik::TreeParams p{theta, 8, 32, kinds[k]};
        pik::LongRangeTree<Accel<T>, Body<T>, Body<T>> tree(p);
        pt::Gravity<T> g{T(e2)};
        tree.calcForceAllAndWriteBack(g, g, ps);
        rms[k] = pt::acc_error(ps, e2).rms;
        n[k] = tree.interactionsEP() + tree.interactionsSP();
      }
      SCOPED_TRACE(std::string(pt::name(d)) + " theta=" + std::to_string(theta));
      EXPECT_LT(n[1], n[0]);
      EXPECT_LE(n[1], n[2]);
      EXPECT_LT(n[2], n[0]);
      EXPECT_LT(rms[2], theta < 0.6 ? 6e-3 : 1.5e-2);
      std::printf("%-9s theta %.1f  rms box %.2e com %.2e offset %.2e  interactions %llu %llu %llu\n",
                  pt::name(d), theta, rms[0], rms[1], rms[2], (unsigned long long)n[0],
                  (unsigned long long)n[1], (unsigned long long)n[2]);
    }
  }
}

template <class T>
std::vector<Accel<T>> forces(const pik::ParticleSystem<Body<T>>& ps) {
  std::vector<Accel<T>> f;
  for (const auto& b : ps) f.push_back({b.acc, b.pot});
  return f;
}
template <class T>
bool bitwise_equal(const std::vector<Accel<T>>& a, const std::vector<Accel<T>>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Accel<T>)) == 0;
}

TYPED_TEST(LongRange, ThreadCountDoesNotChangeResults) {
  using T = TypeParam;
  auto ps = pt::make<T>(Dist::plummer, 3000, 3);
  pik::LongRangeTree<Accel<T>, Body<T>, Body<T>, pik::SPJQuadrupole<T>> tree({0.6, 4, 16});
  const int saved = pik::detail::max_threads();
  std::vector<std::vector<Accel<T>>> results;
  for (int nt : {1, 2, 3}) {
    pik::detail::set_threads(nt);
    tree.calcForceAllAndWriteBack(pt::Gravity<T>{T(eps2)}, pt::GravityQuad<T>{T(eps2)}, ps);
    results.push_back(forces(ps));
  }
  pik::detail::set_threads(saved);
  EXPECT_TRUE(bitwise_equal(results[0], results[1]));
  EXPECT_TRUE(bitwise_equal(results[0], results[2]));
}

TYPED_TEST(LongRange, ListReuseEqualsRebuildWhenNothingMoved) {
  using T = TypeParam;
  auto ps = pt::make<T>(Dist::clustered, 2000, 5);
  pik::LongRangeTree<Accel<T>, Body<T>, Body<T>> tree({0.5, 8, 64});
  pt::Gravity<T> k{T(eps2)};
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::make_for_reuse);
  auto made = forces(ps);
  for (auto& b : ps) b.acc = {}, b.pot = 0;
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::reuse);
  EXPECT_TRUE(bitwise_equal(made, forces(ps)));
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::rebuild);
  EXPECT_TRUE(bitwise_equal(made, forces(ps)));
  // Reused lists after a small move stay close to a rebuild.
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::make_for_reuse);
  for (auto& b : ps) b.pos.x += T(1e-5);
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::reuse);
  auto reused = forces(ps);
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::rebuild);
  auto rebuilt = forces(ps);
  for (std::size_t i = 0; i < reused.size(); ++i)
    ASSERT_LT(pik::norm(pik::vec_cast<pik::Vec3<double>>(reused[i].acc - rebuilt[i].acc)),
              1e-2 * pik::norm(pik::vec_cast<pik::Vec3<double>>(rebuilt[i].acc)));
}

TYPED_TEST(LongRange, ReuseWithoutKeptListsIsAnError) {
  using T = TypeParam;
  auto ps = pt::make<T>(Dist::uniform, 50);
  pik::LongRangeTree<Accel<T>, Body<T>, Body<T>> tree;
  pt::Gravity<T> k{T(eps2)};
  EXPECT_THROW(tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::reuse), pik::Error);
  tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::make_for_reuse);
  ps.add(ps[0]);
  EXPECT_THROW(tree.calcForceAllAndWriteBack(k, k, ps, pik::ListMode::reuse), pik::Error);
}

// The extension point for distributed runs: particles and super-particles handed in
// as imports act on local particles exactly like local particles and cells would.
TYPED_TEST(LongRange, ImportedParticlesAndSuperParticlesActAsSources) {
  using T = TypeParam;
  auto all = pt::make<T>(Dist::uniform, 1200, 11);
  pik::ParticleSystem<Body<T>> local;
  std::vector<Body<T>> remote_near;
  pik::SPJMonopole<T> far_clump;
  pik::Multipole<3> clump;
  for (const auto& b : all) {
    if (b.pos.x < T(0.5)) local.add(b);
    else remote_near.push_back(b);
  }
  // A far clump of mass 0.5 at (100, 0, 0) given as one super-particle.
  clump.mass = 0.5;
  clump.pos = {100, 0, 0};
  far_clump.setMoments(clump);
  pik::LongRangeTree<Accel<T>, Body<T>, Body<T>> tree({0.0, 8, 32});
  tree.setImportedParticles(remote_near);
  tree.setImportedSuperParticles({far_clump});
  pt::Gravity<T> k{T(eps2)};
  tree.calcForceAllAndWriteBack(k, k, local);
  // Oracle: direct sum over all particles plus the clump.
  for (std::size_t i = 0; i < local.size(); i += 37) {
    pik::Vec3<double> a{};
    const auto xi = pik::vec_cast<pik::Vec3<double>>(local[i].pos);
    for (const auto& b : all) {
      pik::Vec3<double> d = xi - pik::vec_cast<pik::Vec3<double>>(b.pos);
      double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2);
      a -= d * (double(b.mass) * rinv * rinv * rinv);
    }
    pik::Vec3<double> d = xi - clump.pos;
    double r2 = pik::norm2(d) + eps2, rinv = 1 / std::sqrt(r2);
    a -= d * (0.5 * rinv * rinv * rinv);
    const double tol = std::is_same_v<T, float> ? 1e-4 : 1e-10;
    EXPECT_LT(pik::norm(pik::vec_cast<pik::Vec3<double>>(local[i].acc) - a), tol * pik::norm(a)) << i;
  }
}

// Moments: a cell's quadrupole built bottom-up equals the quadrupole of its particles.
TEST(Multipole, ParallelAxisShiftMatchesDirectSum) {
  std::mt19937 g(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<std::pair<double, pik::Vec3<double>>> pts;
  for (int i = 0; i < 50; ++i) pts.push_back({0.5 + 0.5 * u(g), {u(g), u(g), u(g)}});
  auto moments = [](auto b, auto e) {
    pik::Multipole<3> m;
    pik::Vec3<double> s{};
    for (auto it = b; it != e; ++it) m.mass += it->first, s += it->second * it->first;
    m.pos = s / m.mass;
    for (auto it = b; it != e; ++it) m.add_quadrupole_of_point(it->first, it->second);
    return m;
  };
  auto whole = moments(pts.begin(), pts.end());
  auto a = moments(pts.begin(), pts.begin() + 20), b = moments(pts.begin() + 20, pts.end());
  pik::Multipole<3> combined;
  combined.mass = a.mass + b.mass;
  combined.pos = (a.pos * a.mass + b.pos * b.mass) / combined.mass;
  combined.add_quadrupole_of(a);
  combined.add_quadrupole_of(b);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(combined.quad[k], whole.quad[k], 1e-12) << k;
  EXPECT_NEAR(whole.quad[0] + whole.quad[1] + whole.quad[2], 0.0, 1e-12);  // traceless
}

}  // namespace
