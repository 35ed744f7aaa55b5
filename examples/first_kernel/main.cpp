// The smallest pik program: a kernel written in .pik (kernels/gravity.pik),
// compiled by pikg-gen for every x86 ISA with run-time dispatch, applied to a
// cloud of particles by direct summation and checked against double precision.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <pik/pik.hpp>

struct Body {
  pik::Vec3<double> pos;
  double mass;
};
struct Accel {
  pik::Vec3<double> acc;
  double pot;
};

#include "Gravity.hpp"

int main(int argc, char**) {
  if (argc > 1) return std::fprintf(stderr, "usage: first_kernel   (no options: 4096 particles, direct sum)\n"), 2;
  const int n = 4096;
  const double eps2 = 1.0 / 4096;
  std::mt19937_64 rng(2026);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Body> body(n);
  for (auto& b : body) b = {{g(rng), g(rng), g(rng)}, 1.0 / n};

  std::vector<Accel> acc(n, Accel{});
  Gravity gravity(eps2);
  auto t0 = std::chrono::steady_clock::now();
  gravity(body.data(), n, body.data(), n, acc.data());
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  double worst = 0;
  for (int i = 0; i < n; ++i) {
    double ax = 0, ay = 0, az = 0;
    for (int j = 0; j < n; ++j) {
      double dx = body[j].pos.x - body[i].pos.x, dy = body[j].pos.y - body[i].pos.y,
             dz = body[j].pos.z - body[i].pos.z;
      double r2 = dx * dx + dy * dy + dz * dz + eps2, rinv = 1 / std::sqrt(r2);
      double s = body[j].mass * rinv * rinv * rinv;
      ax += s * dx, ay += s * dy, az += s * dz;
    }
    double d = std::hypot(acc[i].acc.x - ax, acc[i].acc.y - ay, acc[i].acc.z - az);
    worst = std::fmax(worst, d / std::hypot(ax, ay, az));
  }
  std::printf("pik demo: gravity kernel (%s) on %d particles, %d x %d interactions\n",
              Gravity::isa_name(), n, n, n);
  std::printf("  time %.4f s, %.2f G interactions/s, max relative error vs double %.2e\n", seconds,
              double(n) * n / seconds * 1e-9, worst);
  return worst < 1e-4 ? 0 : 1;
}
