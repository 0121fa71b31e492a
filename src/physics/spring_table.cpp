#include "medspring/physics/spring_table.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <type_traits>

#include "medspring/core/check.hpp"

namespace medspring {

std::vector<int> table_row_order(const std::vector<int>& degree, RowOrder order, int threads) {
  const auto n = static_cast<int>(degree.size());
  if (order == RowOrder::Nodes || n == 0) return {};
  std::vector<int> rows(static_cast<std::size_t>(n));
  for (int a = 0; a < n; ++a) rows[static_cast<std::size_t>(a)] = a;
  auto heavier = [&](int a, int b) {
    return degree[static_cast<std::size_t>(a)] > degree[static_cast<std::size_t>(b)];
  };
  if (order == RowOrder::HeavyLast) {
    std::vector<int> sorted = degree;
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
    const int median = sorted[static_cast<std::size_t>(n / 2)];
    auto heavy = [&](int a) {
      const int d = degree[static_cast<std::size_t>(a)];
      return d > kHeavyDegree && d > 2 * median;
    };
    auto mid = std::stable_partition(rows.begin(), rows.end(), [&](int a) { return !heavy(a); });
    std::stable_sort(mid, rows.end(), heavier);
    return rows;
  }
  require(threads >= 1, "table_row_order: Balanced needs threads >= 1 (got ", threads, ")");
  std::stable_sort(rows.begin(), rows.end(), heavier);
  // Snake deal: sorted row i goes to round j = i / threads, thread t = i % threads (reversed for odd j);
  // thread t's rows are t, t + threads, ...: table row j * threads + t.
  std::vector<int> out(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int j = i / threads, t = i % threads;
    const int in_round = std::min(threads, n - j * threads);
    const int slot = j % 2 == 0 ? t : in_round - 1 - t;
    out[static_cast<std::size_t>(j * threads + slot)] = rows[static_cast<std::size_t>(i)];
  }
  return out;
}

template <class R>
SpringTableArrays<R> make_spring_table(const Model& m, RowOrder order, int threads) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  require(m.bending.size() == 0, m.name, ": the spring table has no bending terms (", m.bending.size(),
          " in the model); step it with the CPU engine");
  const Index n = m.num_nodes(), ns = m.num_springs();
  std::vector<int> degree(static_cast<std::size_t>(n), 0);
  for (Index s = 0; s < ns; ++s) {
    ++degree[static_cast<std::size_t>(m.springs.i[static_cast<std::size_t>(s)])];
    ++degree[static_cast<std::size_t>(m.springs.j[static_cast<std::size_t>(s)])];
  }
  SpringTableArrays<R> T;
  T.nodes = n;
  T.row_node = table_row_order(degree, order, threads);
  std::vector<int> node_row(static_cast<std::size_t>(n));  // inverse of row_node
  for (Index r = 0; r < n; ++r)
    node_row[static_cast<std::size_t>(T.row_node.empty() ? r : T.row_node[static_cast<std::size_t>(r)])] =
        static_cast<int>(r);
  auto node_of = [&](Index r) { return T.row_node.empty() ? r : T.row_node[static_cast<std::size_t>(r)]; };
  const Index slices = (n + hd::kSlice - 1) / hd::kSlice;
  T.slice_begin.resize(static_cast<std::size_t>(slices));
  T.slice_width.resize(static_cast<std::size_t>(slices));
  long long total = 0;
  for (Index sl = 0; sl < slices; ++sl) {
    int w = 0;
    for (Index r = sl * hd::kSlice; r < std::min<Index>(n, (sl + 1) * hd::kSlice); ++r)
      w = std::max(w, degree[static_cast<std::size_t>(node_of(r))]);
    T.slice_begin[static_cast<std::size_t>(sl)] = static_cast<int>(total);
    T.slice_width[static_cast<std::size_t>(sl)] = w;
    total += static_cast<long long>(w) * hd::kSlice;
  }
  require(total < (1ll << 31), m.name, ": spring table of ", total, " entries exceeds 2^31");
  const auto E = static_cast<std::size_t>(total);
  T.other.assign(E, 0);
  T.L0.assign(E, R(0));
  T.k.assign(E, R(0));
  T.kp.assign(E, R(0));
  T.ik.assign(E, R(0));
  // Padding entries point at their row's own node (zero length: skipped). Rows past n: the last row's.
  for (Index sl = 0; sl < slices; ++sl)
    for (int lane = 0; lane < hd::kSlice; ++lane) {
      const Index a = node_of(std::min<Index>(sl * hd::kSlice + lane, n - 1));
      for (int j = 0; j < T.slice_width[static_cast<std::size_t>(sl)]; ++j)
        T.other[static_cast<std::size_t>(T.slice_begin[static_cast<std::size_t>(sl)] + j * hd::kSlice +
                                         lane)] = a;
    }
  std::vector<int> fill(static_cast<std::size_t>(n), 0);
  auto put = [&](Index a, Index b, Index s) {
    const Index r = node_row[static_cast<std::size_t>(a)];
    const Index sl = r / hd::kSlice;
    const auto e =
        static_cast<std::size_t>(T.slice_begin[static_cast<std::size_t>(sl)] +
                                 fill[static_cast<std::size_t>(a)]++ * hd::kSlice + (r - sl * hd::kSlice));
    const auto us = static_cast<std::size_t>(s);
    T.other[e] = b;
    T.L0[e] = static_cast<R>(m.springs.L0[us]);
    T.k[e] = static_cast<R>(m.springs.k[us]);
    T.kp[e] = static_cast<R>(m.springs.kp[us]);
    T.ik[e] = static_cast<R>(m.inv_k[s]);
  };
  for (Index s = 0; s < ns; ++s) {  // increasing s: each node's entries in spring order
    const Index a = m.springs.i[static_cast<std::size_t>(s)], b = m.springs.j[static_cast<std::size_t>(s)];
    put(a, b, s);
    put(b, a, s);
  }
  return T;
}

namespace {

// Each node's springs in spring order: entries start[a] .. start[a+1] of (other end, spring).
struct NodeSprings {
  std::vector<int> degree, start, other, spring;
};

NodeSprings node_springs(const Model& m) {
  const Index n = m.num_nodes(), ns = m.num_springs();
  NodeSprings A;
  A.degree.assign(static_cast<std::size_t>(n), 0);
  A.start.assign(static_cast<std::size_t>(n) + 1, 0);
  for (Index s = 0; s < ns; ++s) {
    ++A.degree[static_cast<std::size_t>(m.springs.i[static_cast<std::size_t>(s)])];
    ++A.degree[static_cast<std::size_t>(m.springs.j[static_cast<std::size_t>(s)])];
  }
  for (Index a = 0; a < n; ++a)
    A.start[static_cast<std::size_t>(a) + 1] =
        A.start[static_cast<std::size_t>(a)] + A.degree[static_cast<std::size_t>(a)];
  A.other.resize(static_cast<std::size_t>(2 * ns));
  A.spring.resize(static_cast<std::size_t>(2 * ns));
  std::vector<int> fill(A.start.begin(), A.start.end() - 1);
  for (Index s = 0; s < ns; ++s) {
    const int a = m.springs.i[static_cast<std::size_t>(s)], b = m.springs.j[static_cast<std::size_t>(s)];
    A.other[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)])] = b;
    A.spring[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = static_cast<int>(s);
    A.other[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)])] = a;
    A.spring[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)]++)] = static_cast<int>(s);
  }
  return A;
}

// A table row: node, its entries begin .. end of NodeSprings, the chunk's slot (-1 whole, -2 padding).
struct Row {
  int node, begin, end, part;
};

// The sliced ELL table of rows given in table order (row_node and the entries; padding entries point
// at the row's own node).
template <class R>
void fill_rows(const Model& m, const NodeSprings& A, const std::vector<Row>& rows, SpringTableArrays<R>& T) {
  const auto R_ = static_cast<Index>(rows.size());
  T.nodes = m.num_nodes();
  T.row_node.resize(rows.size());
  for (Index r = 0; r < R_; ++r)
    T.row_node[static_cast<std::size_t>(r)] = rows[static_cast<std::size_t>(r)].node;
  const Index slices = (R_ + hd::kSlice - 1) / hd::kSlice;
  T.slice_begin.resize(static_cast<std::size_t>(slices));
  T.slice_width.resize(static_cast<std::size_t>(slices));
  long long total = 0;
  for (Index sl = 0; sl < slices; ++sl) {
    int w = 0;
    for (Index r = sl * hd::kSlice; r < std::min<Index>(R_, (sl + 1) * hd::kSlice); ++r)
      w = std::max(w, rows[static_cast<std::size_t>(r)].end - rows[static_cast<std::size_t>(r)].begin);
    T.slice_begin[static_cast<std::size_t>(sl)] = static_cast<int>(total);
    T.slice_width[static_cast<std::size_t>(sl)] = w;
    total += static_cast<long long>(w) * hd::kSlice;
  }
  require(total < (1ll << 31), m.name, ": spring table of ", total, " entries exceeds 2^31");
  const auto E = static_cast<std::size_t>(total);
  T.other.assign(E, 0);
  T.L0.assign(E, R(0));
  T.k.assign(E, R(0));
  T.kp.assign(E, R(0));
  T.ik.assign(E, R(0));
  for (Index sl = 0; sl < slices; ++sl)
    for (int lane = 0; lane < hd::kSlice; ++lane) {
      const Index r = sl * hd::kSlice + lane;
      const Row& row = rows[static_cast<std::size_t>(std::min<Index>(r, R_ - 1))];
      const int w = T.slice_width[static_cast<std::size_t>(sl)];
      for (int j = 0; j < w; ++j) {
        const auto e =
            static_cast<std::size_t>(T.slice_begin[static_cast<std::size_t>(sl)] + j * hd::kSlice + lane);
        T.other[e] = row.node;  // padding: the row's own node (zero length: skipped)
        if (r >= R_ || row.begin + j >= row.end) continue;
        const auto q = static_cast<std::size_t>(row.begin + j);
        const auto us = static_cast<std::size_t>(A.spring[q]);
        T.other[e] = A.other[q];
        T.L0[e] = static_cast<R>(m.springs.L0[us]);
        T.k[e] = static_cast<R>(m.springs.k[us]);
        T.kp[e] = static_cast<R>(m.springs.kp[us]);
        T.ik[e] = static_cast<R>(m.inv_k[A.spring[q]]);
      }
    }
}

void require_network(const Model& m) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  require(m.bending.size() == 0, m.name, ": the spring table has no bending terms (", m.bending.size(),
          " in the model); step it with the CPU engine");
}

}  // namespace

template <class R>
SplitTableArrays<R> make_split_table(const Model& m, int threads, int chunk) {
  require_network(m);
  require(threads >= 1, "make_split_table: threads must be >= 1 (got ", threads, ")");
  const Index n = m.num_nodes(), ns = m.num_springs();
  if (chunk <= 0)
    chunk = std::max(8, static_cast<int>((2 * static_cast<long long>(ns) + threads - 1) / threads));
  const NodeSprings A = node_springs(m);
  // Rows: (node, first entry, end entry, slot); a heavy node's chunks get consecutive slots.
  std::vector<Row> rows;
  SplitTableArrays<R> out;
  out.chunk = chunk;
  out.part_begin.push_back(0);
  for (Index a = 0; a < n; ++a) {
    const int b0 = A.start[static_cast<std::size_t>(a)], d = A.degree[static_cast<std::size_t>(a)];
    if (d <= chunk) {
      rows.push_back({static_cast<int>(a), b0, b0 + d, -1});
      continue;
    }
    out.heavy_node.push_back(static_cast<int>(a));
    for (int c = 0; c < d; c += chunk)
      rows.push_back(
          {static_cast<int>(a), b0 + c, b0 + std::min(d, c + chunk), out.part_begin.back() + c / chunk});
    out.part_begin.push_back(out.part_begin.back() + (d + chunk - 1) / chunk);
  }
  std::vector<int> sizes(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) sizes[r] = rows[r].end - rows[r].begin;
  const std::vector<int> order = table_row_order(sizes, RowOrder::Balanced, threads);
  std::vector<Row> ordered(rows.size());
  out.part.resize(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    ordered[r] = rows[static_cast<std::size_t>(order[r])];
    out.part[r] = ordered[r].part;
  }
  fill_rows(m, A, ordered, out.table);
  return out;
}

template <class R>
GridSplitArrays<R> make_grid_split_table(const Model& m, int chunk) {
  require_network(m);
  const Index n = m.num_nodes();
  const NodeSprings A = node_springs(m);
  if (chunk <= 0 && n > 0) {  // as HeavyLast: heavier than kHeavyDegree and twice the median degree
    std::vector<int> sorted = A.degree;
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
    chunk = std::max(kHeavyDegree, 2 * sorted[static_cast<std::size_t>(n / 2)]);
  }
  std::vector<Row> rows;
  std::vector<int> heavy;
  for (Index a = 0; a < n; ++a) {  // light nodes in node order (locality kept)
    const int b0 = A.start[static_cast<std::size_t>(a)], d = A.degree[static_cast<std::size_t>(a)];
    if (d <= chunk)
      rows.push_back({static_cast<int>(a), b0, b0 + d, -1});
    else
      heavy.push_back(static_cast<int>(a));
  }
  std::stable_sort(heavy.begin(), heavy.end(), [&](int a, int b) {
    return A.degree[static_cast<std::size_t>(a)] > A.degree[static_cast<std::size_t>(b)];
  });
  GridSplitArrays<R> out;
  out.chunk = chunk;
  out.part_begin.push_back(0);
  std::vector<int> lead_of_row;  // heavy index of a lead row
  auto pad_to = [&](std::size_t size) {
    while (rows.size() < size) rows.push_back({rows.empty() ? 0 : rows.back().node, 0, 0, -2});
  };
  if (!heavy.empty()) pad_to((rows.size() + hd::kSlice - 1) / hd::kSlice * hd::kSlice);
  for (std::size_t k = 0; k < heavy.size(); ++k) {
    const int a = heavy[k];
    const int b0 = A.start[static_cast<std::size_t>(a)], d = A.degree[static_cast<std::size_t>(a)];
    const int c = std::max(chunk, (d + hd::kSlice - 1) / hd::kSlice);  // at most a warp of chunks
    const int count = (d + c - 1) / c;
    const std::size_t lane = rows.size() % hd::kSlice;
    if (lane + static_cast<std::size_t>(count) > static_cast<std::size_t>(hd::kSlice))
      pad_to(rows.size() - lane + hd::kSlice);  // a node's chunks never straddle two warps
    out.heavy_node.push_back(a);
    out.lead_row.push_back(static_cast<int>(rows.size()));
    for (int j = 0; j < d; j += c)
      rows.push_back({a, b0 + j, b0 + std::min(d, j + c), out.part_begin.back() + j / c});
    out.part_begin.push_back(out.part_begin.back() + count);
  }
  out.part.resize(rows.size());
  out.lead.assign(rows.size(), -1);
  for (std::size_t r = 0; r < rows.size(); ++r) out.part[r] = rows[r].part;
  for (std::size_t k = 0; k < out.lead_row.size(); ++k)
    out.lead[static_cast<std::size_t>(out.lead_row[k])] = static_cast<int>(k);
  fill_rows(m, A, rows, out.table);
  return out;
}

template SplitTableArrays<double> make_split_table<double>(const Model&, int, int);
template SplitTableArrays<float> make_split_table<float>(const Model&, int, int);
template GridSplitArrays<double> make_grid_split_table<double>(const Model&, int);
template GridSplitArrays<float> make_grid_split_table<float>(const Model&, int);

template <class R>
NodeArrayData<R> make_node_arrays(const Model& m) {
  require(m.finalized, m.name, ": model is not finalized (call finalize or ModelBuilder::build)");
  const Index n = m.num_nodes();
  NodeArrayData<R> N;
  N.nodes = n;
  N.x0.resize(static_cast<std::size_t>(3 * n));
  for (Index q = 0; q < 3 * n; ++q) N.x0[static_cast<std::size_t>(q)] = static_cast<R>(m.x0.data()[q]);
  auto conv = [n](const VecX& v) {
    std::vector<R> out(static_cast<std::size_t>(n));
    for (Index a = 0; a < n; ++a) out[static_cast<std::size_t>(a)] = static_cast<R>(v[a]);
    return out;
  };
  N.mass = conv(m.mass);
  N.damping = conv(m.damping);
  N.kr = conv(m.kr);
  N.fixed.assign(m.fixed.begin(), m.fixed.end());
  N.load_slot.assign(static_cast<std::size_t>(n), -1);
  return N;
}

template SpringTableArrays<double> make_spring_table<double>(const Model&, RowOrder, int);
template SpringTableArrays<float> make_spring_table<float>(const Model&, RowOrder, int);
template NodeArrayData<double> make_node_arrays<double>(const Model&);
template NodeArrayData<float> make_node_arrays<float>(const Model&);

namespace {

// Classes of the triples (a[i], b[i], c[i]), bit for bit, in order of first appearance; false (outputs
// untouched) when there are more than max_classes.
template <class R>
bool classify(const std::vector<R>& a, const std::vector<R>& b, const std::vector<R>& c, int max_classes,
              std::vector<unsigned short>& cls, std::vector<R>& ca, std::vector<R>& cb, std::vector<R>& cc) {
  require(max_classes >= 1 && max_classes <= 65536, "compact parameters: max_classes ", max_classes,
          " outside [1, 65536]");
  using Bits = std::conditional_t<sizeof(R) == 8, std::uint64_t, std::uint32_t>;
  std::map<std::array<Bits, 3>, int> index;
  std::vector<unsigned short> out(a.size());
  std::vector<R> va, vb, vc;
  for (std::size_t i = 0; i < a.size(); ++i) {
    std::array<Bits, 3> key;  // the bit patterns (memcpy: the wasm toolchain's libc++ has no std::bit_cast)
    std::memcpy(&key[0], &a[i], sizeof(Bits));
    std::memcpy(&key[1], &b[i], sizeof(Bits));
    std::memcpy(&key[2], &c[i], sizeof(Bits));
    auto [it, fresh] = index.try_emplace(key, static_cast<int>(va.size()));
    if (fresh) {
      if (static_cast<int>(va.size()) == max_classes) return false;
      va.push_back(a[i]);
      vb.push_back(b[i]);
      vc.push_back(c[i]);
    }
    out[i] = static_cast<unsigned short>(it->second);
  }
  cls = std::move(out);
  ca = std::move(va);
  cb = std::move(vb);
  cc = std::move(vc);
  return true;
}

}  // namespace

template <class R>
bool compact_spring_params(SpringTableArrays<R>& T, int max_classes) {
  if (!T.cls.empty()) return true;
  if (!classify(T.k, T.kp, T.ik, max_classes, T.cls, T.ck, T.ckp, T.cik)) return false;
  T.k = {};
  T.kp = {};
  T.ik = {};
  return true;
}

template <class R>
PackReport pack_spring_table(SpringTableArrays<R>& T, int max_class_bits) {
  require(max_class_bits >= 0 && max_class_bits <= 24,
          "pack_spring_table: max_class_bits must be in 0..24 (got ", max_class_bits, ")");
  PackReport rep;
  if (!T.packed.empty()) {
    rep.fits = true;
    rep.classes = static_cast<long long>(T.cL0.size());
    rep.class_bits = T.class_bits;
    return rep;
  }
  const std::size_t E = T.other.size();
  const bool compact = !T.cls.empty();
  auto param = [&](std::size_t e, int which) -> R {
    if (which == 0) return T.L0[e];
    if (compact) {
      const auto c = T.cls[e];
      return which == 1 ? T.ck[c] : which == 2 ? T.ckp[c] : T.cik[c];
    }
    return which == 1 ? T.k[e] : which == 2 ? T.kp[e] : T.ik[e];
  };
  // Classes: distinct bit patterns of (L0, k, k', 1/k), numbered in order of first appearance.
  using Bits = std::conditional_t<sizeof(R) == 8, std::uint64_t, std::uint32_t>;
  std::map<std::array<Bits, 4>, int> index;
  std::vector<int> cls(E);
  std::vector<std::array<R, 4>> values;
  std::array<Bits, 4> last{};
  int last_class = -1;  // neighbouring entries (a slice's lanes) mostly share a class: skip the lookup
  for (std::size_t e = 0; e < E; ++e) {
    std::array<Bits, 4> key{};
    std::array<R, 4> val{};
    for (int w = 0; w < 4; ++w) {
      val[static_cast<std::size_t>(w)] = param(e, w);
      std::memcpy(&key[static_cast<std::size_t>(w)], &val[static_cast<std::size_t>(w)], sizeof(R));
    }
    if (last_class < 0 || key != last) {
      const auto [it, added] = index.emplace(key, static_cast<int>(values.size()));
      if (added) values.push_back(val);
      last = key;
      last_class = it->second;
    }
    cls[e] = last_class;
  }
  rep.classes = static_cast<long long>(values.size());
  while ((1ll << rep.class_bits) < rep.classes) ++rep.class_bits;
  rep.offset_limit = (1ll << (31 - rep.class_bits)) - 1;
  // Offsets: entry e of slice s, lane l belongs to row s 32 + l (rows past the last: the last row's node,
  // as the table pads them).
  const long long rows = T.row_node.empty() ? T.nodes : static_cast<long long>(T.row_node.size());
  std::vector<long long> offset(E, 0);
  for (std::size_t sl = 0; sl < T.slice_begin.size(); ++sl)
    for (int lane = 0; lane < hd::kSlice; ++lane) {
      const long long r = std::min<long long>(static_cast<long long>(sl) * hd::kSlice + lane, rows - 1);
      const long long a = T.row_node.empty() ? r : T.row_node[static_cast<std::size_t>(r)];
      for (int j = 0; j < T.slice_width[sl]; ++j) {
        const auto e = static_cast<std::size_t>(T.slice_begin[sl] + j * hd::kSlice + lane);
        offset[e] = T.other[e] - a;
        rep.max_offset = std::max(rep.max_offset, std::abs(offset[e]));
      }
    }
  if (rep.class_bits > max_class_bits || rep.max_offset > rep.offset_limit) return rep;
  rep.fits = true;
  T.packed.resize(E);
  for (std::size_t e = 0; e < E; ++e)
    T.packed[e] = (static_cast<unsigned>(static_cast<int>(offset[e])) << rep.class_bits) |
                  static_cast<unsigned>(cls[e]);
  T.class_bits = rep.class_bits;
  T.cL0.resize(values.size());
  T.ck.resize(values.size());
  T.ckp.resize(values.size());
  T.cik.resize(values.size());
  for (std::size_t c = 0; c < values.size(); ++c) {
    T.cL0[c] = values[c][0];
    T.ck[c] = values[c][1];
    T.ckp[c] = values[c][2];
    T.cik[c] = values[c][3];
  }
  T.other = {};
  T.L0 = {};
  T.k = {};
  T.kp = {};
  T.ik = {};
  T.cls = {};
  return rep;
}

template PackReport pack_spring_table<double>(SpringTableArrays<double>&, int);
template PackReport pack_spring_table<float>(SpringTableArrays<float>&, int);

template <class R>
bool compact_node_params(NodeArrayData<R>& N, int max_classes) {
  if (!N.cls.empty()) return true;
  if (!classify(N.mass, N.damping, N.kr, max_classes, N.cls, N.cmass, N.cdamping, N.ckr)) return false;
  N.mass = {};
  N.damping = {};
  N.kr = {};
  return true;
}

template bool compact_spring_params<double>(SpringTableArrays<double>&, int);
template bool compact_spring_params<float>(SpringTableArrays<float>&, int);
template bool compact_node_params<double>(NodeArrayData<double>&, int);
template bool compact_node_params<float>(NodeArrayData<float>&, int);

LoadSlots make_load_slots(const std::vector<PointLoad>& loads, Index n) {
  validate_loads(loads, n);
  LoadSlots S;
  S.slot.assign(static_cast<std::size_t>(n), -1);
  for (const PointLoad& L : loads) {
    int& s = S.slot[static_cast<std::size_t>(L.node)];
    if (s < 0) {
      s = static_cast<int>(S.nodes.size());
      S.nodes.push_back(L.node);
    }
  }
  return S;
}

void load_rows(const std::vector<PointLoad>& loads, const LoadSlots& slots, double t, double* rows) {
  std::fill(rows, rows + 3 * slots.nodes.size(), 0.0);
  for (const PointLoad& L : loads) {
    const double s = L.scale(t);
    if (s == 0.0) continue;
    double* r = rows + 3 * slots.slot[static_cast<std::size_t>(L.node)];
    r[0] += s * L.force[0];
    r[1] += s * L.force[1];
    r[2] += s * L.force[2];
  }
}

}  // namespace medspring
