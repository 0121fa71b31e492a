// Spring laws: linear and Duffing (eq. 5), with the unit-consistent Duffing coefficient of D-3.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "medspring/core/params.hpp"
#include "medspring/physics/kernels.hpp"

namespace medspring {

/// How the cubic coefficient k' of eq. (5) is chosen for a spring of stiffness k and rest length L0 (D-3).
enum class DuffingMode {
  Linear,        // k' = 0
  Strain,        // default: k' = eta k / L0^2 (cubic = linear at 100 % strain for eta = 1)
  Absolute,      // the paper's literal k' = k / length^2 with length = 10 mm (k' = 0.01 k numerically)
  ScaledStrain,  // k' = k / (100 L0^2): listed for completeness, nonlinearity invisible (rejected reading)
};

struct DuffingSettings {
  DuffingMode mode = DuffingMode::Strain;
  double eta = 1.0;      // Strain mode strength (dimensionless)
  double length = 10.0;  // Absolute mode Duffing length (mm): k' = k / length^2
  bool soft = false;     // soft spring (k' < 0, clamped beyond its peak, §1.7) instead of hard
};

/// k' (N/mm^3) for a spring of stiffness k (N/mm) and rest length L0 (mm).
double duffing_coefficient(double k, double L0, const DuffingSettings& s);

DuffingMode parse_duffing_mode(const std::string& text);
std::string to_string(DuffingMode mode);
inline DuffingMode parse_enum(const std::string& text, DuffingMode*) {
  return parse_duffing_mode(text);
}

/// The declaration of DuffingSettings (core/params.hpp): JSON object "duffing" of the model parameters.
template <ParamOf<DuffingSettings> S, class V>
void for_each_field(S& s, V&& v) {
  v(ParamSpec{"mode", "",
              "k' rule (D-3): linear, strain, absolute (the paper's k' = k / length^2) or scaled_strain"},
    s.mode);
  v(ParamSpec{"eta", "", "strain mode strength: k' = eta k / L0^2"}.positive(), s.eta);
  v(ParamSpec{"length", "mm", "absolute mode Duffing length: k' = k / length^2"}.positive(), s.length);
  v(ParamSpec{"soft", "", "soft spring (k' < 0, clamped beyond its peak, §1.7) instead of hard"}, s.soft);
}

/// Peak elongation of a soft spring, Delta* = sqrt(k / (3|k'|)); +inf for hard/linear springs.
inline double soft_limit(double k, double kp) {
  return kp < 0 ? std::sqrt(k / (3.0 * -kp)) : std::numeric_limits<double>::infinity();
}

/// Scalar tension phi(Delta) = k Delta + k' Delta^3 (eq. 5), with the soft-spring clamp of §1.7:
/// for |Delta| > Delta* (k' < 0) phi = sign(Delta) phi(Delta*).
inline double spring_tension(double k, double kp, double delta) {
  return hd::spring_tension(k, kp, delta);  // written once for the CPU and the GPU (kernels.hpp)
}

/// d phi / d Delta = k + 3 k' Delta^2 (0 beyond the soft-spring peak).
inline double spring_tension_derivative(double k, double kp, double delta) {
  return hd::spring_tension_derivative(k, kp, delta);
}

/// Potential energy V(Delta) = k Delta^2 / 2 + k' Delta^4 / 4 (continued linearly in phi beyond the
/// soft-spring peak so that -dV/dx stays the clamped force).
inline double spring_energy(double k, double kp, double delta) {
  if (kp < 0) {
    const double ds = soft_limit(k, kp);
    const double ad = std::abs(delta);
    if (ad > ds) {
      const double phi_s = k * ds + kp * ds * ds * ds;
      return 0.5 * k * ds * ds + 0.25 * kp * ds * ds * ds * ds + phi_s * (ad - ds);
    }
  }
  const double d2 = delta * delta;
  return 0.5 * k * d2 + 0.25 * kp * d2 * d2;
}

}  // namespace medspring
