// Short-range tree: neighbour lists and kernel candidate lists against brute force,
// for every search mode, open, periodic and partly periodic boundaries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include "support.hpp"

namespace {

using pt::Accel;
using pt::Body;
using Mode = pik::SearchMode;

/// Brute-force neighbours of particle i: every particle j and periodic image k with
/// |x_i - (x_j + k L)| < r (r by the mode), distances in double as the tree does.
template <class T>
std::vector<std::size_t> brute(const pik::ParticleSystem<Body<T>>& ps, std::size_t i, Mode m,
                               const pik::Boundary<3>& b) {
  std::vector<std::size_t> out;
  int K[3];
  double rmax = 0;
  for (auto& p : ps) rmax = std::max(rmax, double(p.r));
  for (int d = 0; d < 3; ++d) K[d] = b.periodic[d] ? int(std::ceil(rmax / b.period(d))) + 1 : 0;
  for (std::size_t j = 0; j < ps.size(); ++j) {
    double r = m == Mode::gather ? double(ps[i].r)
               : m == Mode::scatter ? double(ps[j].r)
                                    : std::max(double(ps[i].r), double(ps[j].r));
    for (int a = -K[0]; a <= K[0]; ++a)
      for (int c = -K[1]; c <= K[1]; ++c)
        for (int e = -K[2]; e <= K[2]; ++e) {
          const int k[3] = {a, c, e};
          double d2 = 0;
          for (int d = 0; d < 3; ++d) {
            const double s = double(k[d]) * (b.periodic[d] ? b.period(d) : 0.0);
            const double dx = double(ps[i].pos[d]) - (double(ps[j].pos[d]) + s);
            d2 += dx * dx;
          }
          if (d2 < r * r) out.push_back(j);
        }
  }
  return out;
}

template <class T>
pik::ParticleSystem<Body<T>> cloud(int n, double rmin, double rmax, unsigned seed) {
  auto ps = pt::make<T>(pt::Dist::uniform, n, seed);
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(rmin, rmax);
  for (auto& p : ps) p.r = T(u(g));
  return ps;
}

struct Case {
  Mode mode;
  bool px, py, pz;
  double rmin, rmax;
};

template <class T>
class ShortRange : public ::testing::Test {};
using Reals = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ShortRange, Reals);

template <class T, Mode M>
void check_case(const Case& c) {
  auto ps = cloud<T>(600, c.rmin, c.rmax, 17);
  const pik::Boundary<3> b = (c.px || c.py || c.pz)
                                 ? pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}, {c.px, c.py, c.pz})
                                 : pik::Boundary<3>::open();
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> tree({0.5, 4, 16}, b);
  tree.calcForceAllAndWriteBack(pt::CountNeighbours<T, M>{}, ps);
  std::vector<std::size_t> got;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    auto want = brute(ps, i, M, b);
    tree.neighbourIndices(ps[i], got);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "particle " << i;
    if constexpr (std::is_same_v<T, double>) {  // kernel sees shifted copies in T
      ASSERT_EQ(double(ps[i].pot), double(want.size())) << "kernel count, particle " << i;
    }
  }
}

template <class T>
void check_all(const Case& c) {
  SCOPED_TRACE(std::string(pik::to_string(c.mode)) + " periodic " + std::to_string(c.px) +
               std::to_string(c.py) + std::to_string(c.pz) + " r " + std::to_string(c.rmax));
  if (c.mode == Mode::gather) check_case<T, Mode::gather>(c);
  if (c.mode == Mode::scatter) check_case<T, Mode::scatter>(c);
  if (c.mode == Mode::symmetric) check_case<T, Mode::symmetric>(c);
}

TYPED_TEST(ShortRange, NeighbourListsEqualBruteForce) {
  for (Mode m : {Mode::gather, Mode::scatter, Mode::symmetric}) {
    check_all<TypeParam>({m, false, false, false, 0.02, 0.15});
    check_all<TypeParam>({m, true, true, true, 0.02, 0.15});
    check_all<TypeParam>({m, true, false, true, 0.02, 0.15});
  }
}

// Radii larger than the periodic box: every image in range counts.
TYPED_TEST(ShortRange, SearchRadiusLargerThanBox) {
  for (Mode m : {Mode::gather, Mode::symmetric}) {
    check_all<TypeParam>({m, true, true, true, 1.1, 1.6});
    check_all<TypeParam>({m, false, false, false, 1.1, 3.0});
  }
}

template <class T, Mode M>
std::vector<Accel<T>> run_mode(pik::ParticleSystem<Body<T>> ps, const pik::Boundary<3>& b) {
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, M> tree({0.5, 8, 32}, b);
  // A kernel whose result depends on the order of the j's: any difference in the
  // candidate lists shows.
  auto k = [](const Body<T>* pi, int ni, const Body<T>* pj, int nj, Accel<T>* f) {
    for (int i = 0; i < ni; ++i)
      for (int j = 0; j < nj; ++j) {
        auto d = pi[i].pos - pj[j].pos;
        f[i].acc += d * (T(1) + T(j) * T(1e-3));
        f[i].pot = f[i].pot * T(0.5) + pik::norm2(d);
      }
  };
  tree.calcForceAllAndWriteBack(k, ps);
  std::vector<Accel<T>> out;
  for (auto& p : ps) out.push_back({p.acc, p.pot});
  return out;
}

// With one radius for every particle, gather, scatter and symmetric must hand the
// kernel the same candidates in the same order: bitwise identical results.
TYPED_TEST(ShortRange, ModesAgreeBitwiseWithEqualRadii) {
  using T = TypeParam;
  for (bool periodic : {false, true}) {
    auto ps = cloud<T>(800, 0.08, 0.08, 23);
    auto b = periodic ? pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}) : pik::Boundary<3>::open();
    auto g = run_mode<T, Mode::gather>(ps, b);
    auto s = run_mode<T, Mode::scatter>(ps, b);
    auto y = run_mode<T, Mode::symmetric>(ps, b);
    EXPECT_EQ(std::memcmp(g.data(), s.data(), g.size() * sizeof(g[0])), 0) << "periodic " << periodic;
    EXPECT_EQ(std::memcmp(g.data(), y.data(), g.size() * sizeof(g[0])), 0) << "periodic " << periodic;
  }
}

TYPED_TEST(ShortRange, ThreadCountAndReuse) {
  using T = TypeParam;
  auto ps = cloud<T>(1000, 0.03, 0.1, 29);
  auto b = pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1});
  pik::ShortRangeTree<Accel<T>, Body<T>, Body<T>, Mode::symmetric> tree({0.5, 8, 32}, b);
  pt::CountNeighbours<T, Mode::symmetric> k;
  const int saved = pik::detail::max_threads();
  pik::detail::set_threads(1);
  tree.calcForceAllAndWriteBack(k, ps, pik::ListMode::make_for_reuse);
  std::vector<T> one;
  for (auto& p : ps) one.push_back(p.pot);
  pik::detail::set_threads(2);
  tree.calcForceAllAndWriteBack(k, ps, pik::ListMode::reuse);
  for (std::size_t i = 0; i < ps.size(); ++i) ASSERT_EQ(one[i], ps[i].pot);
  tree.calcForceAllAndWriteBack(k, ps);
  pik::detail::set_threads(saved);
  for (std::size_t i = 0; i < ps.size(); ++i) ASSERT_EQ(one[i], ps[i].pot);
}

TEST(ShortRangeErrors, ParticleOutsidePeriodicBoxIsNamed) {
  auto ps = cloud<double>(20, 0.1, 0.1, 3);
  ps[13].pos.y = 1.5;
  pik::ShortRangeTree<Accel<double>, Body<double>, Body<double>, Mode::gather> tree(
      {}, pik::Boundary<3>::periodic_box({0, 0, 0}, {1, 1, 1}));
  try {
    tree.build(ps);
    FAIL() << "no error";
  } catch (const pik::Error& e) {
    EXPECT_NE(std::string(e.what()).find("particle 13 lies outside the periodic box"), std::string::npos)
        << e.what();
  }
}

}  // namespace
