// A particle with a NaN position must stop every rank with a message naming it
// (registered with PASS_REGULAR_EXPRESSION in CMakeLists.txt).
#include <cmath>
#include <limits>
#include <vector>

#include <pik/Vec.hpp>
#include <pik/comm/Environment.hpp>
#include <pik/domain/ParticleExchange.hpp>

struct Particle {
  pik::Vec3<double> pos;
};

int main(int argc, char** argv) {
  pik::Environment env(argc, argv);
  const auto comm = env.world();
  pik::DomainInfo<double, 3> dom(comm);
  std::vector<Particle> ps(3, Particle{{0.5, 0.5, 0.5}});
  if (comm.rank() == comm.size() - 1) ps[2].pos.y = std::numeric_limits<double>::quiet_NaN();
  pik::exchange_particles(ps, dom);
  return 0;  // not reached
}
