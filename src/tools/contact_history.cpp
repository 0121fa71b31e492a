// ContactModel's contact history (checkpoints, docs/tools.md): what the contact model carries from one
// update to the next -- previous surface, tool poses, grasps, persistent-contact flags, multipliers -- as a
// versioned binary record. Split from contact.cpp (collision and response).
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/tools/contact.hpp"

namespace medspring {

namespace {
// v2 adds each tool's `touching` flag (persistent contact); v1 histories resume with it false.
constexpr char kHistoryTag[] = "medspring-contact-history-v2";
constexpr char kHistoryTagV1[] = "medspring-contact-history-v1";
}  // namespace

std::string ContactModel::save_history() const {
  ByteWriter w;
  w.str(kHistoryTag);
  w.i64(prev_.rows());
  w.flag(have_prev_);
  w.doubles(prev_.data(), static_cast<Index>(prev_.size()));
  w.u64(tools_.size());
  for (const ToolSlot& t : tools_) {
    const ToolState& st = t.state;
    w.i32(static_cast<std::int32_t>(st.tool.kind));
    w.f64(st.tool.radius);
    w.f64(st.tool.length);
    w.f64(st.tool.opening);
    for (const Pose* p : {&st.pose, &t.prev}) {
      w.doubles(p->position.data(), 3);
      w.doubles(p->rotation.coeffs().data(), 4);
    }
    w.flag(st.grasping);
    w.flag(t.touching);
    w.u64(t.held.size());
    for (const Attachment& h : t.held) {
      w.i64(h.triangle);
      w.doubles(h.bary.data(), 3);
      w.doubles(h.anchor.data(), 3);
    }
  }
  w.u64(lambda_nodes_.size());
  for (const Index n : lambda_nodes_) {
    w.i64(n);
    w.f64(lambda_[n]);
  }
  return std::move(w.bytes());
}

void ContactModel::restore_history(std::string_view bytes, const std::string& what) {
  ByteReader r(bytes, what, "contact history");
  const std::string tag = r.str("tag");
  if (tag != kHistoryTag && tag != kHistoryTagV1) r.fail("not a contact history");
  const bool v1 = tag == kHistoryTagV1;
  const Index nv = static_cast<Index>(forces_.force.rows());
  const Index rows = static_cast<Index>(r.i64());
  if (rows != nv)
    throw InvalidInput(cat(what, ": saved for a surface of ", rows, " nodes, this one has ", nv));
  const bool have_prev = r.flag("have_prev");
  MatX3 prev(nv, 3);
  r.doubles(prev.data(), static_cast<Index>(prev.size()));
  if (!prev.allFinite()) r.fail("non-finite surface");
  const std::uint64_t nt = r.u64();
  if (nt != tools_.size())
    throw InvalidInput(cat(what, ": saved with ", nt, " tools, this run has ", tools_.size()));
  std::vector<ToolSlot> tools = tools_;
  for (std::size_t k = 0; k < tools.size(); ++k) {
    ToolSlot& t = tools[k];
    const int kind = r.i32();
    const double radius = r.f64(), length = r.f64(), opening = r.f64();
    if (kind != static_cast<int>(t.state.tool.kind) || radius != t.state.tool.radius ||
        length != t.state.tool.length)
      throw InvalidInput(cat(what, ": tools[", k, "] differs from the saved one"));
    if (!(std::isfinite(opening) && opening >= 0 && opening <= std::numbers::pi)) r.fail("bad opening");
    t.state.tool.opening = opening;
    for (Pose* p : {&t.state.pose, &t.prev}) {
      r.doubles(p->position.data(), 3);
      r.doubles(p->rotation.coeffs().data(), 4);
      if (!p->position.allFinite() || !p->rotation.coeffs().allFinite()) r.fail("non-finite pose");
    }
    t.state.grasping = r.flag("grasping");
    t.touching = v1 ? false : r.flag("touching");
    const Index nh = r.count("held", 8 + 6 * 8);
    t.held.clear();
    for (Index j = 0; j < nh; ++j) {
      Attachment h;
      h.triangle = static_cast<Index>(r.i64());
      r.doubles(h.bary.data(), 3);
      r.doubles(h.anchor.data(), 3);
      if (h.triangle < 0 || h.triangle >= F_.rows() || !h.bary.allFinite() || !h.anchor.allFinite())
        r.fail("bad grasp attachment");
      t.held.push_back(h);
    }
    t.state.attached = static_cast<Index>(t.held.size());
  }
  const Index nl = r.count("multipliers", 16);
  std::vector<std::pair<Index, double>> lambda;
  for (Index j = 0; j < nl; ++j) {
    const Index n = static_cast<Index>(r.i64());
    const double l = r.f64();
    if (n < 0 || n >= nv || !(std::isfinite(l) && l >= 0)) r.fail("bad multiplier");
    lambda.emplace_back(n, l);
  }
  r.finish();
  // commit
  prev_ = std::move(prev);
  have_prev_ = have_prev;
  for (std::size_t k = 0; k < tools.size(); ++k) {
    tools[k].held.reserve(static_cast<std::size_t>(2 * F_.rows()));
    tools_[k] = std::move(tools[k]);
  }
  for (const Index n : lambda_nodes_) lambda_[n] = 0;
  lambda_nodes_.clear();
  for (const auto& [n, l] : lambda) {
    lambda_[n] = l;
    lambda_nodes_.push_back(n);
  }
}

}  // namespace medspring
