// Gravity for a million particles: a Plummer sphere, one Barnes-Hut force step with
// the kernel of kernels/gravity.pik (generated for every x86 ISA, chosen at run time).
// Usage: gravity_million [N]   (default 1048576)
#include <cstdio>
#include <cstdlib>
#include <random>

#include <pik/pik.hpp>

struct Pull {  // what the kernel computes
  pik::Vec3<float> acc;
  float pot;
  void clear() { acc = {}, pot = 0; }
};
struct Star {  // the particle: position, mass, result
  pik::Vec3<float> pos;
  float mass;
  Pull pull;
  pik::Vec3<float> getPos() const { return pos; }
  float getCharge() const { return mass; }
  void copyFromFP(const Star& s) { pos = s.pos, mass = s.mass; }
  void copyFromForce(const Pull& p) { pull = p; }
};
using Cell = pik::SPJMonopole<float>;

#include "Gravity.hpp"
#include "GravityCells.hpp"

int main(int argc, char** argv) {
  char* end = nullptr;
  const long n = argc > 1 ? std::strtol(argv[1], &end, 10) : 1L << 20;
  if (argc > 2 || (argc > 1 && (*end || end == argv[1] || n < 1 || n > 1L << 31)))
    return std::fprintf(stderr, "usage: gravity_million [N]   (N: particles, 1 to 2^31; default 1048576)\n"), 2;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  pik::ParticleSystem<Star> stars;
  for (long i = 0; i < n; ++i) {  // Plummer sphere, scale radius 1, total mass 1
    float r;
    do r = 1 / std::sqrt(std::pow(u(rng), -2.0f / 3) - 1);
    while (!(r < 20));  // cut the infinite tail
    float z = 2 * u(rng) - 1, ph = 6.2831853f * u(rng);
    float s = std::sqrt(1 - z * z);
    stars.add({{r * s * std::cos(ph), r * s * std::sin(ph), r * z}, 1.0f / n, {}});
  }
  const float eps2 = 1e-4f;
  pik::LongRangeTree<Pull, Star, Star, Cell> tree({.theta = 0.5, .n_leaf_limit = 8, .n_group_limit = 64});
  const double t0 = pik::wall_time();
  try {
    tree.calcForceAllAndWriteBack(Gravity(eps2), GravityCells(eps2), stars);
  } catch (const pik::Error& e) {
    return std::fprintf(stderr, "gravity_million: %s\n", e.what()), 1;
  }
  const double t = pik::wall_time() - t0;

  double energy = 0;
  for (const Star& s : stars) energy += 0.5 * s.mass * s.pull.pot;
  std::printf("gravity_million: %ld particles, kernel %s, %.3f s, %.0f interactions/particle\n", n,
              Gravity::isa_name(), t, double(tree.interactionsEP() + tree.interactionsSP()) / n);
  std::printf("  potential energy %.6f (untruncated Plummer sphere, eps = 0: -3 pi / 32 = %.6f)\n", energy, -3 * M_PI / 32);
  return 0;
}
