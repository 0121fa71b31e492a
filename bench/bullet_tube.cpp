// Bullet's btSoftBody on the comparison tube (benchmark-only; the MedSpring libraries never link Bullet).
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>

#include <algorithm>
#include <memory>

#include "compare.hpp"
#include "medspring/core/check.hpp"

namespace medspring::bench {

namespace {

struct BulletTube {
  btSoftBodyWorldInfo info;
  std::unique_ptr<btSoftBody> body;
  btVector3 load;
  int load_node = 0;
  btScalar dt = 0.5;
  void update() {
    body->addForce(load, load_node);  // cleared by predictMotion: applied every step, like the held load
    body->predictMotion(dt);
    body->solveConstraints();
    body->integrateMotion();
  }
};

}  // namespace

std::function<void()> make_bullet_update(const TubeData& d, std::string& settings, double& bytes_per_node) {
  auto b = std::make_shared<BulletTube>();
  b->info.m_gravity.setValue(0, 0, 0);
  b->info.air_density = 0;
  b->info.water_density = 0;
  b->info.m_sparsesdf.Initialize();
  const auto n = static_cast<std::size_t>(d.nodes());
  std::vector<btVector3> x(n);
  std::vector<btScalar> m(n);
  for (std::size_t a = 0; a < n; ++a) {
    x[a].setValue(static_cast<btScalar>(d.x0[3 * a]), static_cast<btScalar>(d.x0[3 * a + 1]),
                  static_cast<btScalar>(d.x0[3 * a + 2]));
    m[a] = d.fixed[a] ? 0 : static_cast<btScalar>(d.mass[a]);  // mass 0: anchored
  }
  b->body = std::make_unique<btSoftBody>(&b->info, static_cast<int>(n), x.data(), m.data());
  // Link stiffness: Bullet's links are position projections, one per iteration, moving the ends by the
  // fraction kLST of the length error. A spring k over a step h moves them by k h^2 (1/m_a + 1/m_b) of it
  // (for small values), so kLST = min(1, k h^2 (1/m_a + 1/m_b)) with the tube's uniform k and mass.
  const double k = d.k.empty() ? 0.0 : d.k[0];
  const double mass = d.mass.empty() ? 1.0 : d.mass[0];
  const double kLST = std::min(1.0, k * d.dt * d.dt * 2.0 / mass);
  btSoftBody::Material* mat = b->body->appendMaterial();
  mat->m_kLST = static_cast<btScalar>(kLST);
  mat->m_kAST = 0;
  mat->m_kVST = 0;
  for (std::size_t s = 0; s < d.si.size(); ++s) b->body->appendLink(d.si[s], d.sj[s], mat, false);
  b->body->m_cfg.piterations = 1;
  b->body->m_cfg.kDP = 0;  // default (no damping); MedSpring's node damping has no Bullet equivalent
  b->body->m_cfg.collisions = 0;
  b->load.setValue(static_cast<btScalar>(d.load[0]), static_cast<btScalar>(d.load[1]),
                   static_cast<btScalar>(d.load[2]));
  b->load_node = static_cast<int>(d.load_node);
  b->dt = static_cast<btScalar>(d.dt);
  settings =
      cat("btSoftBody, btDefaultSoftBodySolver path (predictMotion, solveConstraints, integrateMotion), "
          "piterations 1, kLST ",
          kLST, " (k h^2 (1/m_a + 1/m_b)), kDP 0, no collisions, ",
          sizeof(btScalar) == 8 ? "double" : "single", " precision, one step of ", d.dt, " ms");
  bytes_per_node = (static_cast<double>(n) * (sizeof(btSoftBody::Node) + 2 * sizeof(btDbvtNode)) +
                    static_cast<double>(d.si.size()) * sizeof(btSoftBody::Link)) /
                   static_cast<double>(n);
  return [b] { b->update(); };
}

}  // namespace medspring::bench
