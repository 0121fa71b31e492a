#include "medspring/tools/contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

// Regions of a closest point on a triangle: 0 face, 1..3 edge (v_e, v_e+1) + 1, 4..6 vertex + 4.
constexpr int kFace = 0;

// Closest point of p on triangle (a, b, c) (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary,
                         int& region) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    bary = {1, 0, 0};
    region = 4;
    return a;
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) {
    bary = {0, 1, 0};
    region = 5;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    bary = {1 - v, v, 0};
    region = 1;
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) {
    bary = {0, 0, 1};
    region = 6;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    bary = {1 - w, 0, w};
    region = 3;
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bary = {0, 1 - w, w};
    region = 2;
    return b + w * (c - b);
  }
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  bary = {1 - v - w, v, w};
  region = kFace;
  return a + ab * v + ac * w;
}

// Closest points of segments p1-q1 and p2-q2 (Ericson 5.1.9): parameters s, t in [0, 1].
void closest_segments(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, double& s, double& t) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double eps = 1e-14;
  if (a <= eps && e <= eps) {
    s = t = 0;
    return;
  }
  if (a <= eps) {
    s = 0;
    t = std::clamp(f / e, 0.0, 1.0);
    return;
  }
  const double c = d1.dot(r);
  if (e <= eps) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
    return;
  }
  const double b = d1.dot(d2), denom = a * e - b * b;
  s = denom > eps * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1) {
    t = 1;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

Vec3 row(const MatX3& X, Index i) {
  return X.row(i).transpose();
}

// Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom & Strackee).
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  return 2 * std::atan2(num, den);
}

}  // namespace

void validate_contact_settings(const ContactSettings& s) {
  validate_params(s, "contact");  // the ranges declared in contact.hpp
}

ContactModel::ContactModel(const MatX3i& faces, const MatX3& rest, const ContactSettings& settings)
    : settings_(settings), F_(faces) {
  validate_contact_settings(settings);
  require(faces.rows() > 0 && rest.rows() > 0, "contact: empty surface");
  require_finite_points(rest, "contact: rest surface");
  const Index nf = static_cast<Index>(faces.rows()), nv = static_cast<Index>(rest.rows());
  area_.resize(nf);
  VecX node_area = VecX::Zero(nv);
  double volume = 0;
  std::vector<Index> count(static_cast<std::size_t>(nv) + 1, 0);
  for (Index t = 0; t < nf; ++t) {
    for (int k = 0; k < 3; ++k) require_index(faces(t, k), nv, "contact: faces[", t, "]");
    const Vec3 a = row(rest, faces(t, 0)), b = row(rest, faces(t, 1)), c = row(rest, faces(t, 2));
    area_[t] = 0.5 * (b - a).cross(c - a).norm();
    volume += a.dot(b.cross(c)) / 6;
    for (int k = 0; k < 3; ++k) {
      node_area[faces(t, k)] += area_[t];
      ++count[static_cast<std::size_t>(faces(t, k)) + 1];
    }
  }
  orient_ = volume >= 0 ? 1.0 : -1.0;
  // vertex -> faces
  vf_start_.assign(count.begin(), count.end());
  for (std::size_t i = 1; i < vf_start_.size(); ++i) vf_start_[i] += vf_start_[i - 1];
  vf_.resize(static_cast<std::size_t>(3 * nf));
  std::vector<Index> fill(vf_start_.begin(), vf_start_.end() - 1);
  for (Index t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k)
      vf_[static_cast<std::size_t>(fill[static_cast<std::size_t>(faces(t, k))]++)] = t;
  // face across each edge
  adj_face_.assign(static_cast<std::size_t>(3 * nf), -1);
  for (Index t = 0; t < nf; ++t)
    for (int e = 0; e < 3; ++e) {
      const Index u = faces(t, e), w = faces(t, (e + 1) % 3);
      for (Index j = vf_start_[static_cast<std::size_t>(u)]; j < vf_start_[static_cast<std::size_t>(u) + 1];
           ++j) {
        const Index o = vf_[static_cast<std::size_t>(j)];
        if (o == t) continue;
        if (faces(o, 0) == w || faces(o, 1) == w || faces(o, 2) == w)
          adj_face_[static_cast<std::size_t>(3 * t + e)] = o;
      }
    }
  // stable penalty (explicit, held over dt): k_p A_i dt^2 / m <= kappa
  const double a_max = 1.5 * node_area.maxCoeff();  // margin for stretched triangles
  require(a_max > 0, "contact: the surface has no area");
  k_limit_ = 4.0 * settings.min_mass / (settings.dt * settings.dt * a_max);
  if (settings.stiffness > 0) {
    require(settings.stiffness <= k_limit_, "contact.stiffness: ", settings.stiffness,
            " N/mm^3 is above the stable limit ", k_limit_, " N/mm^3 for dt = ", settings.dt, " ms");
    k_p_ = settings.stiffness;
  } else {
    k_p_ = settings.kappa / 4.0 * k_limit_;
  }
  bvh_ = SurfaceBvh(faces, rest);
  forces_.force = MatX3::Zero(nv, 3);
  forces_.nodes.reserve(static_cast<std::size_t>(nv));
  touched_.assign(static_cast<std::size_t>(nv), 0);
  node_w_ = VecX::Zero(nv);
  node_wd_ = VecX::Zero(nv);
  lambda_ = VecX::Zero(nv);
  node_fn_ = MatX3::Zero(nv, 3);
  node_tool_.assign(static_cast<std::size_t>(nv), 0);
  lambda_nodes_.reserve(static_cast<std::size_t>(nv));
  candidates_.reserve(static_cast<std::size_t>(nf));
  prev_ = rest;
}

Index ContactModel::add_tool(const Tool& tool, const Pose& pose) {
  const Index k = num_tools();
  validate_tool(tool, cat("tools[", k, "]"));
  ToolSlot slot;
  slot.state.tool = tool;
  slot.state.pose = checked_pose(pose, cat("tools[", k, "].pose"));
  slot.prev = slot.state.pose;
  slot.held.reserve(static_cast<std::size_t>(2 * F_.rows()));  // both jaws
  tools_.push_back(std::move(slot));
  contacts_.reserve(static_cast<std::size_t>(2 * F_.rows()) * tools_.size());
  sub_.reserve(contacts_.capacity());
  return k;
}

void ContactModel::set_pose(Index k, const Pose& pose) {
  require_index(k, num_tools(), "contact: tool");
  tools_[static_cast<std::size_t>(k)].state.pose = checked_pose(pose, cat("tools[", k, "].pose"));
}

void ContactModel::reset_history() {
  have_prev_ = false;
  for (ToolSlot& t : tools_) {
    t.prev = t.state.pose;
    t.touching = false;
  }
  for (const Index n : lambda_nodes_) lambda_[n] = 0;
  lambda_nodes_.clear();
}

void ContactModel::set_opening(Index k, double opening) {
  require_index(k, num_tools(), "contact: tool");
  Tool& t = tools_[static_cast<std::size_t>(k)].state.tool;
  require(t.kind == ToolKind::Grasper, "tools[", k, "]: only a grasper has an opening (this is a ",
          to_string(t.kind), ")");
  require(std::isfinite(opening) && opening >= 0 && opening <= std::numbers::pi, "tools[", k,
          "].opening: must be in [0, pi] rad (got ", opening, ")");
  t.opening = opening;
}

void ContactModel::check_outside(const MatX3& S, const Tool& tool, const Pose& pose,
                                 const std::string& what) const {
  require(S.rows() == forces_.force.rows(), what, ": surface has ", S.rows(), " nodes, expected ",
          forces_.force.rows());
  Capsule caps[2];
  const int n = primitives(tool, checked_pose(pose, what), caps);
  for (int p = 0; p < n; ++p)
    for (const Vec3& q : {caps[p].a, caps[p].b}) {
      const double w = winding(S, q);
      require(w < 0.5, what, " starts inside the organ (axis point ", q.x(), ", ", q.y(), ", ", q.z(),
              " mm): place it outside the surface");
    }
}

double ContactModel::winding(const MatX3& S, const Vec3& q) const {
  double w = 0;
  for (Index t = 0; t < F_.rows(); ++t)
    w += solid_angle(row(S, F_(t, 0)) - q, row(S, F_(t, 1)) - q, row(S, F_(t, 2)) - q);
  return w * orient_ / (4 * std::numbers::pi);
}

double ContactModel::nearest_distance(const MatX3& S, const Vec3& q) const {
  double best = std::numeric_limits<double>::infinity();
  Vec3 bary;
  int region = 0;
  for (Index t = 0; t < F_.rows(); ++t)
    best = std::min(
        best, (q - closest_on_triangle(q, row(S, F_(t, 0)), row(S, F_(t, 1)), row(S, F_(t, 2)), bary, region))
                  .squaredNorm());
  return std::sqrt(best);
}

Vec3 ContactModel::pseudo_normal(const MatX3& S, Index tri, int region) const {
  auto face_normal = [&](Index t) {
    const Vec3 a = row(S, F_(t, 0));
    const Vec3 n = orient_ * (row(S, F_(t, 1)) - a).cross(row(S, F_(t, 2)) - a);
    const double l = n.norm();
    return l > 0 ? Vec3(n / l) : Vec3::Zero();
  };
  if (region == kFace) return face_normal(tri);
  if (region <= 3) {
    const Index o = adj_face_[static_cast<std::size_t>(3 * tri + region - 1)];
    return face_normal(tri) + (o >= 0 ? face_normal(o) : Vec3::Zero());
  }
  const Index v = F_(tri, region - 4);
  Vec3 n = Vec3::Zero();
  for (Index j = vf_start_[static_cast<std::size_t>(v)]; j < vf_start_[static_cast<std::size_t>(v) + 1]; ++j)
    n += face_normal(vf_[static_cast<std::size_t>(j)]);
  return n;
}

void ContactModel::add_force(Index tri, const Vec3& bary, const Vec3& f) {
  for (int k = 0; k < 3; ++k) {
    const Index n = F_(tri, k);
    if (!touched_[static_cast<std::size_t>(n)]) {
      touched_[static_cast<std::size_t>(n)] = 1;
      forces_.nodes.push_back(n);
    }
    forces_.force.row(n) += bary[k] * f.transpose();
  }
}

bool ContactModel::collide(const Capsule& cap, const Capsule& cap_prev, int tool, int part, const MatX3& S,
                           double reach, bool inside) {
  ToolSlot& slot = tools_[static_cast<std::size_t>(tool)];
  const double r = cap.r, max_depth = settings_.max_depth * r, dt = settings_.dt;
  // candidates: boxes overlapping the swept capsule (this pose and the last update's)
  const Vec3 lo = cap.a.cwiseMin(cap.b).cwiseMin(cap_prev.a).cwiseMin(cap_prev.b).array() - reach;
  const Vec3 hi = cap.a.cwiseMax(cap.b).cwiseMax(cap_prev.a).cwiseMax(cap_prev.b).array() + reach;
  candidates_.clear();
  bvh_.query(lo, hi, candidates_);
  const Pose& pose = slot.state.pose;
  const bool segment = (cap.b - cap.a).squaredNorm() > 1e-24;
  bool any = false;
  for (const Index t : candidates_) {
    const Vec3 v[3] = {row(S, F_(t, 0)), row(S, F_(t, 1)), row(S, F_(t, 2))};
    Vec3 bary, best_bary, p, q;
    int region = 0, best_region = 0;
    double best = std::numeric_limits<double>::infinity(), signed_dist = 0;
    Vec3 normal;
    bool crossing = false;
    if (segment) {
      const Vec3 n = orient_ * (v[1] - v[0]).cross(v[2] - v[0]);
      const double ln = n.norm();
      if (ln > 0) {
        const double ha = n.dot(cap.a - v[0]) / ln, hb = n.dot(cap.b - v[0]) / ln;
        if ((ha < 0) != (hb < 0)) {
          const Vec3 x = cap.a + ha / (ha - hb) * (cap.b - cap.a);
          Vec3 bx;
          int rx = 0;
          const Vec3 px = closest_on_triangle(x, v[0], v[1], v[2], bx, rx);
          if (rx == kFace || (px - x).squaredNorm() < 1e-20) {
            crossing = true;
            p = px;
            best_bary = bx;
            signed_dist = std::min(ha, hb);
            normal = n / ln;
          }
        }
      }
    }
    if (!crossing) {
      const int ends = segment ? 2 : 1;
      for (int e = 0; e < ends; ++e) {
        const Vec3& x = e == 0 ? cap.a : cap.b;
        const Vec3 px = closest_on_triangle(x, v[0], v[1], v[2], bary, region);
        const double d = (x - px).squaredNorm();
        if (d < best) {
          best = d, p = px, q = x, best_bary = bary, best_region = region;
        }
      }
      if (segment)
        for (int e = 0; e < 3; ++e) {
          double s = 0, u = 0;
          closest_segments(cap.a, cap.b, v[e], v[(e + 1) % 3], s, u);
          const Vec3 x = cap.a + s * (cap.b - cap.a), px = v[e] + u * (v[(e + 1) % 3] - v[e]);
          const double d = (x - px).squaredNorm();
          if (d < best) {
            best = d, p = px, q = x;
            best_bary.setZero();
            best_bary[e] = 1 - u;
            best_bary[(e + 1) % 3] = u;
            best_region = u <= 0 ? 4 + e : u >= 1 ? 4 + (e + 1) % 3 : 1 + e;
          }
        }
      const double dist = std::sqrt(best);
      if (dist >= reach) continue;
      const Vec3 pn = pseudo_normal(S, t, best_region);
      const double lpn = pn.norm();
      const bool outside = pn.dot(q - p) >= 0;
      if (outside && dist > 1e-9 * r) {  // a sphere around the closest feature
        signed_dist = dist;
        normal = (q - p) / dist;
      } else {  // behind the surface: depth along the feature's pseudo-normal (smooth across edges)
        normal = lpn > 0 ? Vec3(pn / lpn) : Vec3::UnitZ();
        signed_dist = normal.dot(q - p);
      }
    }
    double depth = r - signed_dist;
    if (!(depth > 0 && (depth <= max_depth || inside))) continue;
    depth = std::min(depth, max_depth);  // inside: the kept contacts push with at most max_depth
    // velocities: surface point and the tool's material point at the axis point nearest to it
    Vec3 v_surf = Vec3::Zero();
    for (int k = 0; k < 3; ++k) v_surf += best_bary[k] * (row(S, F_(t, k)) - row(prev_, F_(t, k)));
    v_surf /= dt;
    const Vec3 axis_pt = p + (r - depth) * normal;  // tool axis point behind the contact
    const Vec3 local = pose.rotation.conjugate() * (axis_pt - pose.position);
    const Vec3 v_tool = (axis_pt - slot.prev.apply(local)) / dt;
    const Vec3 w = v_tool - v_surf;      // tool relative to the tissue
    const double rate = -w.dot(normal);  // d(depth)/dt
    const double A = area_[t];
    const double fn = std::max(0.0, A * k_p_ * (depth + settings_.damping * dt * rate));
    Vec3 f = -fn * normal;  // on the tissue
    if (settings_.friction > 0 && fn > 0) {
      const Vec3 wt = w - w.dot(normal) * normal;
      const double mu_fn = settings_.friction * fn;
      const double v_eps = std::max(settings_.slip_velocity, mu_fn * dt / settings_.min_mass);
      f += mu_fn * wt / std::max(wt.norm(), v_eps);  // drags the tissue along with the tool
    }
    Contact c;
    c.triangle = t;
    c.tool = tool;
    c.part = part;
    c.point = p;
    c.bary = best_bary;
    c.normal = normal;
    c.depth = depth;
    c.area = A;
    c.force = f;
    if (contacts_.size() < contacts_.capacity()) {
      contacts_.push_back(c);
      SubContact sc;
      sc.fn0 = sc.fn = fn;
      sc.depth = depth;
      sub_.push_back(sc);
    }
    add_force(t, best_bary, f);
    for (int j = 0; j < 3; ++j) {
      const Index nd = F_(t, j);
      node_w_[nd] += best_bary[j] * A;
      node_wd_[nd] += best_bary[j] * A * depth;
      node_fn_.row(nd) -= best_bary[j] * fn * normal.transpose();
      node_tool_[static_cast<std::size_t>(nd)] = tool;
    }
    ToolState& st = slot.state;
    st.force -= f;
    st.torque += (p - pose.position).cross(-f);
    st.area += A;
    st.triangle_penetration = std::max(st.triangle_penetration, depth);
    ++st.contacts;
    any = true;
  }
  return any;
}

void ContactModel::update(const MatX3& S) {
  require(S.rows() == forces_.force.rows(), "contact: surface has ", S.rows(), " nodes, expected ",
          forces_.force.rows());
  bvh_.refit(S);
  if (!have_prev_) {
    prev_ = S;
    have_prev_ = true;
  }
  for (const Index n : forces_.nodes) {
    forces_.force.row(n).setZero();
    node_fn_.row(n).setZero();
    node_w_[n] = node_wd_[n] = 0;
    touched_[static_cast<std::size_t>(n)] = 0;
  }
  forces_.nodes.clear();
  contacts_.clear();
  sub_.clear();
  sub_open_ = sub_changed_ = false;
  const double dt = settings_.dt;
  for (Index k = 0; k < num_tools(); ++k) {
    ToolSlot& slot = tools_[static_cast<std::size_t>(k)];
    ToolState& st = slot.state;
    const Index first_contact = static_cast<Index>(contacts_.size());
    st.force.setZero();
    st.torque.setZero();
    st.grasp_force.setZero();
    st.area = st.penetration = st.triangle_penetration = 0;
    st.contacts = 0;
    st.inside = false;
    Capsule caps[2], prev_caps[2];
    const int n = primitives(st.tool, st.pose, caps);
    primitives(st.tool, slot.prev, prev_caps);
    for (int p = 0; p < n; ++p) collide(caps[p], prev_caps[p], static_cast<int>(k), p, S, caps[p].r, false);
    // Persistent contact (no tunnelling, docs/tools.md): a tool that touched the tissue at the last
    // update and finds no triangle within r now is either outside (released) or has passed through the
    // surface between two updates while the tissue moved. The winding number tells which; inside, the
    // contacts are kept with the triangles that the axis is behind, within r/4 of the nearest surface's
    // distance, with their depth capped at max_depth r, until regular contacts are found again or the
    // tool is outside.
    if (st.contacts == 0 && slot.touching)
      for (int p = 0; p < n; ++p) {
        double d_near = std::numeric_limits<double>::infinity();
        for (const Vec3& q : {caps[p].a, caps[p].b})
          if (winding(S, q) >= 0.5) d_near = std::min(d_near, nearest_distance(S, q));
        if (!std::isfinite(d_near)) continue;
        st.inside = true;
        collide(caps[p], prev_caps[p], static_cast<int>(k), p, S, d_near + 0.25 * caps[p].r, true);
      }
    slot.touching = st.contacts > 0;
    if (st.tool.kind == ToolKind::Grasper) {
      const bool closed = st.tool.opening <= settings_.grasp_angle;
      if (closed && !st.grasping) {  // the jaws close: hold what they touch
        slot.held.clear();
        for (std::size_t c = static_cast<std::size_t>(first_contact); c < contacts_.size(); ++c)
          slot.held.push_back({contacts_[c].triangle, contacts_[c].bary,
                               st.pose.rotation.conjugate() * (contacts_[c].point - st.pose.position)});
        st.grasping = !slot.held.empty();
      } else if (!closed) {
        st.grasping = false;
        slot.held.clear();
      }
      for (const Attachment& h : slot.held) {
        Vec3 p = Vec3::Zero(), v_p = Vec3::Zero();
        for (int j = 0; j < 3; ++j) {
          p += h.bary[j] * row(S, F_(h.triangle, j));
          v_p += h.bary[j] * (row(S, F_(h.triangle, j)) - row(prev_, F_(h.triangle, j)));
        }
        v_p /= dt;
        const Vec3 anchor = st.pose.apply(h.anchor);
        const Vec3 v_a = (anchor - slot.prev.apply(h.anchor)) / dt;
        const Vec3 f = area_[h.triangle] * k_p_ * ((anchor - p) + settings_.damping * dt * (v_a - v_p));
        add_force(h.triangle, h.bary, f);
        st.grasp_force -= f;
        st.force -= f;
        st.torque += (p - st.pose.position).cross(-f);
      }
      st.attached = static_cast<Index>(slot.held.size());
    }
    slot.prev = st.pose;
  }
  // augmented Lagrangian: multipliers of the nodes in contact grow with their penetration
  for (const Index n : lambda_nodes_)
    if (node_w_[n] <= 0) lambda_[n] = 0;  // left the contact
  lambda_nodes_.clear();
  const std::size_t in_contact = forces_.nodes.size();
  for (std::size_t j = 0; j < in_contact; ++j) {
    const Index n = forces_.nodes[j];
    const double fn = node_fn_.row(n).norm();
    if (node_w_[n] <= 0 || fn <= 0) {
      lambda_[n] = 0;
      continue;
    }
    // signed depth of the node inside its tool (negative: outside)
    ToolState& st = tools_[static_cast<std::size_t>(node_tool_[static_cast<std::size_t>(n)])].state;
    Capsule caps[2];
    const int np = primitives(st.tool, st.pose, caps);
    const Vec3 x = row(S, n);
    double d = -std::numeric_limits<double>::infinity();
    for (int p = 0; p < np; ++p) {
      const Vec3 ab = caps[p].b - caps[p].a;
      const double l2 = ab.squaredNorm();
      const double s = l2 > 0 ? std::clamp((x - caps[p].a).dot(ab) / l2, 0.0, 1.0) : 0.0;
      d = std::max(d, caps[p].r - (x - caps[p].a - s * ab).norm());
    }
    st.penetration = std::max(st.penetration, d);
    lambda_[n] = std::max(0.0, lambda_[n] + settings_.multiplier * k_p_ * node_w_[n] * d);
    if (lambda_[n] <= 0) continue;
    lambda_nodes_.push_back(n);
    const Vec3 f = lambda_[n] * node_fn_.row(n).transpose() / fn;
    forces_.force.row(n) += f.transpose();
    st.force -= f;
    st.torque += (row(S, n) - st.pose.position).cross(-f);
  }
  forces_.total.setZero();
  forces_.centre = -1;
  double best = 0;
  for (const Index n : forces_.nodes) {
    const Vec3 f = forces_.force.row(n).transpose();
    forces_.total += f;
    if (f.squaredNorm() > best) best = f.squaredNorm(), forces_.centre = n;
  }
  prev_ = S;
}

bool ContactModel::substep(const MatX3& S, double t, MatX3& delta) {
  if (!settings_.substep || contacts_.empty()) return false;
  auto at = [&](const Contact& c) {
    Vec3 p = Vec3::Zero();
    for (int k = 0; k < 3; ++k) p += c.bary[k] * row(S, F_(c.triangle, k));
    return p;
  };
  if (!sub_open_) {  // the frame start: the forces are the update's
    sub_open_ = true;
    sub_t0_ = sub_t_ = t;
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      sub_[i].p0 = at(contacts_[i]);
      sub_[i].t = t;
    }
    return false;
  }
  for (const Index n : forces_.nodes) delta.row(n).setZero();
  const double c_p = settings_.damping * settings_.dt;
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const Contact& c = contacts_[i];
    SubContact& sc = sub_[i];
    sc.impulse += sc.fn * (t - sub_t_);
    const double d = c.depth + c.normal.dot(at(c) - sc.p0);  // re-projected along the held normal
    const double rate = t > sc.t ? (d - sc.depth) / (t - sc.t) : 0.0;
    if (t > sc.t) sc.depth = d, sc.t = t;
    const double fn = std::max(0.0, c.area * k_p_ * (d + c_p * rate));
    const Vec3 df = -(fn - sc.fn) * c.normal;  // change of the force on the tissue
    sc.fn = fn;
    for (int k = 0; k < 3; ++k) delta.row(F_(c.triangle, k)) += c.bary[k] * df.transpose();
  }
  sub_t_ = t;
  sub_changed_ = true;
  return true;
}

void ContactModel::end_frame(double t) {
  if (!sub_changed_) return;
  sub_changed_ = sub_open_ = false;
  const double T = t - sub_t0_;
  if (!(T > 0)) return;
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    Contact& c = contacts_[i];
    SubContact& sc = sub_[i];
    sc.impulse += sc.fn * (t - sub_t_);
    const Vec3 df = -(sc.impulse / T - sc.fn0) * c.normal;  // average minus the update's, on the tissue
    c.force += df;
    forces_.total += df;
    ToolState& st = tools_[static_cast<std::size_t>(c.tool)].state;
    st.force -= df;
    st.torque += (c.point - st.pose.position).cross(-df);
  }
}

}  // namespace medspring
