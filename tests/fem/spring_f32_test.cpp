// The gather pass's springs in single precision (issue 23, src/physics/spring_f32.hpp,
// docs/volumetric-speed.md "Float springs") against the double slots (spring_chunk_forces: the gather pass's
// double arithmetic), on a cube and the kidney phantom, linear and with the Duffing term, from stretch to
// squeezed and with noise. Per spring the tolerance follows from float rounding: the length change comes from
// the displacements (rounded to float, relative eps_f each) and the force from it, so
//   |f32 - f64| <= 16 eps_f (phi'(d) (|u_i| + |u_j| + |D|) + |phi(d)|),
// phi(d) = d (k + k' d^2) the tension, D = u_j - u_i, and 16 the roundings on the way (plus the double
// slot's own rounding of L - L0). At rest every slot is the double one to double rounding (both k times
// |x0_j - x0_i| - L0, a few roundings of L0); eight springs a vector and one at a time give the same bits (no
// FMA contraction in that file).
#include "spring_f32.hpp"  // src/physics

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <random>

#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/physics/integrators.hpp"
#include "medspring/physics/state.hpp"
#include "spring_gather.hpp"  // src/physics
#include "volumetric_fixtures.hpp"

using namespace medspring;
using medspring::testing::squeezed;

namespace {

struct SlotCheck {
  double worst = 0;    // max over springs of |f32 - f64| / the spring's bound (must be <= 1)
  double rel_inf = 0;  // max |f32 - f64| / max |f64| (reported)
  double stiff32 = 0, stiff64 = 0;
  double max32 = 0;  // max |f32| over the slots
};

SlotCheck check_slots(const Model& m, const MatX3& x, const std::string& label) {
  const Index n = m.num_nodes(), ns = m.num_springs();
  const SpringsF32& S = m.volume_f32->springs;
  EXPECT_EQ(S.size(), static_cast<std::size_t>(ns)) << label;
  std::vector<float> u(static_cast<std::size_t>(4 * n));
  detail::fill_displacements_f32(*m.volume_f32, x.data(), u.data());
  const auto nslots = static_cast<std::size_t>(4 * (2 * ns + 1));
  std::vector<float> f8(nslots, 7.0f), f1(nslots, 7.0f);
  SlotCheck out;
  out.stiff32 = detail::spring_slots_f32(S, u.data(), f8.data(), true, true);
  EXPECT_EQ(detail::spring_slots_f32(S, u.data(), f1.data(), true, false), out.stiff32) << label;
  EXPECT_EQ(std::memcmp(f8.data(), f1.data(), nslots * sizeof(float)), 0)
      << label << ": eight a vector and one at a time differ";
  EXPECT_EQ(detail::spring_slots_f32(S, u.data(), f1.data(), false, true), 1.0) << label;
  for (std::size_t q = 0; q < 4; ++q) EXPECT_EQ(f8[8 * static_cast<std::size_t>(ns) + q], 0.0f) << label;
  std::vector<double> f64(static_cast<std::size_t>(4 * ns));
  std::int64_t bits = 0;
  detail::spring_chunk_forces(m, 0, ns, x.data(), f64.data(), true, bits);
  std::memcpy(&out.stiff64, &bits, sizeof bits);
  out.stiff64 = std::max(1.0, out.stiff64);
  constexpr double eps = std::numeric_limits<float>::epsilon();
  double dmax = 0, fmax = 0;
  for (Index s = 0; s < ns; ++s) {
    const auto q = static_cast<std::size_t>(4 * s), qj = static_cast<std::size_t>(4 * (ns + s));
    const Vec3 ui = x.row(m.springs.i[s]) - m.x0.row(m.springs.i[s]);
    const Vec3 uj = x.row(m.springs.j[s]) - m.x0.row(m.springs.j[s]);
    const double L = (x.row(m.springs.j[s]) - x.row(m.springs.i[s])).norm();
    const double d = L - m.springs.L0[s], k = m.springs.k[s], kp = m.springs.kp[s];
    // the float rounding, and the double slot's own (its L - L0 at rest is 0 to a few double roundings)
    const double bound = 16 * eps *
                             ((k + 3 * kp * d * d) * (ui.norm() + uj.norm() + (uj - ui).norm()) +
                              std::abs(d * (k + kp * d * d))) +
                         8 * std::numeric_limits<double>::epsilon() * k * L;
    double di = 0;
    for (std::size_t c = 0; c < 3; ++c) {
      out.max32 = std::max(out.max32, std::abs(static_cast<double>(f8[q + c])));
      di = std::max(di, std::abs(static_cast<double>(f8[q + c]) - f64[q + c]));
      EXPECT_EQ(f8[qj + c], -f8[q + c]) << label << ", spring " << s;  // exactly the negation
    }
    EXPECT_EQ(f8[q + 3], 0.0f) << label << ", spring " << s;
    if (di > 0)
      out.worst = std::max(out.worst, bound > 0 ? di / bound : std::numeric_limits<double>::infinity());
    dmax = std::max(dmax, di);
    fmax = std::max(fmax, Vec3(f64[q], f64[q + 1], f64[q + 2]).norm());
  }
  out.rel_inf = fmax > 0 ? dmax / fmax : dmax;
  EXPECT_LE(out.worst, 1.0) << label;
  EXPECT_LE(std::abs(out.stiff32 - out.stiff64), 1e-5 * out.stiff64) << label;
  std::cout << label << ": max |df| / max |f| " << out.rel_inf << ", worst spring's |df| / bound "
            << out.worst << ", stiffening " << out.stiff32 << " (double " << out.stiff64 << ")\n";
  return out;
}

}  // namespace

TEST(SpringF32, SlotsWithinTheRoundingBoundOfTheDoubleSlots) {
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0.0, 0.2);
  const VolumetricMesh cube =
      fem::volumetric_mesh(medspring::testing::box_surface(4, 20), {.target_nodes = 300});
  const SurfaceMesh ks = kidney_phantom();
  const VolumetricMesh kidney = fem::volumetric_mesh(ks, {.target_nodes = 800});
  for (const bool duffing : {false, true}) {
    VolumetricSettings st;
    if (duffing) st.duffing = DuffingSettings{DuffingMode::Strain, 1.0, 10.0, false};  // hard springs
    for (const auto* vm : {&cube, &kidney}) {
      st.fixed = {0, 1, 2, 3};
      const VolumetricBody body(*vm, st, vm == &cube ? "cube" : "kidney phantom");
      const Model& m = body.model();
      ASSERT_TRUE(m.volume_f32 != nullptr);
      ASSERT_EQ(m.has_soft_springs, false);
      const std::string name =
          std::string(vm == &cube ? "cube" : "kidney phantom") + (duffing ? ", Duffing" : "");
      {  // at rest: the slot is k c (c = |x0_j - x0_i| - L0, a few double roundings of L0: the double slot
         // at rest is of that size too), so force-free to double rounding
        const SlotCheck r = check_slots(m, m.x0, name + ", at rest");
        double kl = 0;
        for (Index q = 0; q < m.num_springs(); ++q) kl = std::max(kl, m.springs.k[q] * m.springs.L0[q]);
        EXPECT_LE(r.max32, 16 * std::numeric_limits<double>::epsilon() * kl) << name;
        EXPECT_NEAR(r.stiff32, 1.0, 1e-6) << name;
      }
      for (const double strain : {-0.1, 0.001, 0.01, 0.1, 0.5, 0.3}) {
        MatX3 x = squeezed(m.x0, strain);
        if (strain == 0.3) x += MatX3::NullaryExpr(m.num_nodes(), 3, [&] { return N(rng); });
        const SlotCheck r = check_slots(m, x, name + ", strain " + std::to_string(strain));
        EXPECT_GT(r.rel_inf, 0.0);  // the float arithmetic ran
        EXPECT_LT(r.rel_inf, 64 * std::numeric_limits<float>::epsilon());
        if (duffing && strain >= 0.1) {
          EXPECT_GT(r.stiff64, 1.0);  // stretched or squeezed hard springs stiffen
        }
      }
    }
  }
}

// The step with the float springs (the default with volume_precision "float") against the same step with
// double springs (detail::set_gather_springs_f32(false); the volume passes float in both): the kidney phantom
// (800 nodes, supports on the bottom 20 %), 0.5 N on its top node, 300 frames of 0.5 ms. The positions differ
// (the float springs ran) but stay within 1e-5 of the peak displacement, with the same sub-steps and
// warnings.
TEST(SpringF32, StepWithFloatSpringsStaysWithinToleranceOfDoubleSprings) {
  const SurfaceMesh s = kidney_phantom();
  VolumetricSettings vs;
  vs.fixed = medspring::testing::bottom_supports(s);
  const VolumetricMesh vm = fem::volumetric_mesh(s, {.target_nodes = 800});
  const VolumetricBody body(vm, vs, "kidney");
  const Model& m = body.model();
  ASSERT_TRUE(m.volume_f32 != nullptr);
  ASSERT_FALSE(m.gather.empty());  // the gather pass, whose springs are float
  const Index top = medspring::testing::top_node(s);
  State a = make_state(m), b = make_state(m);
  body.transfer_force(top, Vec3(0, 0, -0.5), a.f_ext);
  b.f_ext = a.f_ext;
  double disp = 0, dev = 0;
  for (int i = 0; i < 300; ++i) {
    const bool was = detail::set_gather_springs_f32(false);
    step(m, a, {.dt = 0.5});
    detail::set_gather_springs_f32(true);
    step(m, b, {.dt = 0.5});
    detail::set_gather_springs_f32(was);
    ASSERT_EQ(a.substeps, b.substeps) << "frame " << i;
    ASSERT_TRUE(b.x.allFinite()) << "frame " << i;
    disp = std::max(disp, (a.x - m.x0).cwiseAbs().maxCoeff());
    dev = std::max(dev, (a.x - b.x).cwiseAbs().maxCoeff());
  }
  std::cout << "300 frames, 0.5 N: peak displacement " << disp
            << " mm, float springs - double springs at most " << dev << " mm (" << dev / disp << " of it), "
            << a.substeps << " sub-steps\n";
  EXPECT_GT(disp, 1.0);
  EXPECT_GT(dev, 0.0);  // the float springs ran
  EXPECT_LE(dev, 1e-5 * disp);
  EXPECT_EQ(a.warnings.total(), b.warnings.total());
  EXPECT_EQ(a.warnings.inverted_elements, b.warnings.inverted_elements);
}

// Float slots take half the bytes of double ones, so a model with the float volume pass and float springs
// gets the gather pass up to twice the springs (kSpringGatherMaxSpringsF32, spring_gather.hpp): the kidney
// phantom at 3,807 nodes (about 26k springs) has one with float, none with double, and set_volume_single_
// precision rebuilds it either way. Its step with the gather pass (float springs) against the same body
// built without (the scatter pass, double springs): the same sub-steps, positions within 1e-5 of the peak.
TEST(SpringF32, FloatSlotsTakeTheGatherPassToTwiceTheSprings) {
  const SurfaceMesh s = kidney_phantom();
  VolumetricSettings vs;
  vs.fixed = medspring::testing::bottom_supports(s);
  const VolumetricMesh vm = fem::volumetric_mesh(s, {.target_nodes = 4000});
  const VolumetricBody body(vm, vs, "kidney");
  const Model& m = body.model();
  ASSERT_GT(m.num_springs(), kSpringGatherMaxSprings);
  ASSERT_LE(m.num_springs(), detail::kSpringGatherMaxSpringsF32);
  ASSERT_TRUE(m.volume_f32 != nullptr);
  EXPECT_FALSE(m.gather.empty());
  Model dbl = m;
  set_volume_single_precision(dbl, false);
  EXPECT_TRUE(dbl.gather.empty());
  set_volume_single_precision(dbl, true);
  EXPECT_FALSE(dbl.gather.empty());
  EXPECT_EQ(dbl.gather.row, m.gather.row);
  const Index was = detail::set_spring_gather_max_f32(kSpringGatherMaxSprings);
  const VolumetricBody scatter(vm, vs, "kidney, scatter pass");
  detail::set_spring_gather_max_f32(was);
  ASSERT_TRUE(scatter.model().gather.empty());
  const Index top = medspring::testing::top_node(s);
  State a = make_state(m), b = make_state(scatter.model());
  body.transfer_force(top, Vec3(0, 0, -0.5), a.f_ext);
  b.f_ext = a.f_ext;
  double disp = 0, dev = 0;
  for (int i = 0; i < 60; ++i) {
    step(m, a, {.dt = 0.5});
    step(scatter.model(), b, {.dt = 0.5});
    ASSERT_EQ(a.substeps, b.substeps) << "frame " << i;
    disp = std::max(disp, (a.x - m.x0).cwiseAbs().maxCoeff());
    dev = std::max(dev, (a.x - b.x).cwiseAbs().maxCoeff());
  }
  std::cout << m.num_nodes() << " nodes, " << m.num_springs() << " springs, 60 frames: peak " << disp
            << " mm, gather - scatter at most " << dev << " mm\n";
  EXPECT_GT(disp, 0.5);
  EXPECT_GT(dev, 0.0);
  EXPECT_LE(dev, 1e-5 * disp);
}
