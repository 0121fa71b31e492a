#include "medspring/medial/chain.hpp"

#include <algorithm>

#include "medspring/core/check.hpp"

namespace medspring {

Model make_chain_model(const MatX3& C0, const ChainSettings& s, const std::string& name) {  // §5.2
  const Index n = static_cast<Index>(C0.rows());
  return make_chain_model(C0, s, name, VecX::Constant(std::max<Index>(n, 0), s.kb));
}

Model make_chain_model(const MatX3& C0, const ChainSettings& s, const std::string& name, const VecX& kb) {
  const Index n = static_cast<Index>(C0.rows());
  require(n >= 2, name, ": a chain needs at least 2 atoms (got ", n, ")");
  require_finite_points(C0, cat(name, ": atom"));
  require_nonnegative(s.k, cat(name, ": chain.k"));
  require_nonnegative(s.kr, cat(name, ": chain.kr"));
  require_positive(s.mass, cat(name, ": chain.mass"));
  require_nonnegative(s.beta, cat(name, ": chain.beta"));
  require_nonnegative(s.kb, cat(name, ": chain.kb"));
  require(kb.size() == n, name, ": ", kb.size(), " bending stiffnesses for ", n, " atoms");
  for (Index i = 0; i < n; ++i) require_nonnegative(kb[i], cat(name, ": atom ", i, ": bending stiffness"));
  const DuffingSettings duffing = s.nonlinear ? s.duffing : DuffingSettings{.mode = DuffingMode::Linear};
  ModelBuilder b(name);
  for (Index i = 0; i < n; ++i) {
    const bool fixed = (i == 0 && s.fix_first) || (i == n - 1 && s.fix_last);
    b.add_node(C0.row(i).transpose(), s.mass, s.beta * s.mass, s.kr, fixed);
  }
  for (Index i = 0; i + 1 < n; ++i) {
    const double L0 = (C0.row(i + 1) - C0.row(i)).norm();
    require(L0 >= 1e-9, name, ": atoms ", i, " and ", i + 1, " coincide (", L0, " mm apart)");
    b.add_spring(i, i + 1, s.k, duffing);  // D-3 / D-4
  }
  for (Index i = 1; i + 1 < n; ++i)
    if (kb[i] > 0) b.add_bending(i - 1, i, i + 1, kb[i]);
  return b.build();
}

}  // namespace medspring
