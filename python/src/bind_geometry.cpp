// Geometry layer: SurfaceMesh, validation, normals, phantoms, topology, centerlines, label volumes.
#include "bind_common.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/geometry/polyline.hpp"
#include "medspring/geometry/surface_mesh.hpp"
#include "medspring/geometry/topology.hpp"
#include "medspring/geometry/volume.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

Mat3 mat3_arg(py::handle obj, const std::string& name) {
  const std::string expected = "a finite float64 array of shape (3, 3)";
  py::array a;
  try {
    a = py::module_::import("numpy").attr("asarray")(obj, "dtype"_a = "float64");
  } catch (const py::error_already_set&) {
    throw InvalidInput(cat(name, ": expected ", expected, "; got ", describe_object(obj)));
  }
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw InvalidInput(cat(name, ": expected ", expected, "; got ", describe_object(obj)));
  const auto d = a.cast<py::array_t<double>>();
  Mat3 R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = d.at(r, c);
  if (!R.allFinite()) throw InvalidInput(cat(name, ": expected ", expected, "; got non-finite values"));
  return R;
}

SurfaceMesh make_mesh(py::handle V, py::handle F) {
  SurfaceMesh mesh;
  mesh.V = points_arg(V, "V");
  mesh.F = faces_arg(F, "F", static_cast<Index>(mesh.V.rows()));
  return mesh;
}

template <class T>
void bind_volume(py::module_& m, const char* name, const char* what) {
  using Vol = VolumeT<T>;
  py::class_<Vol>(m, name,
                  cat("A ", what,
                      " volume with voxel spacing, origin and orientation (immutable).\n\n"
                      "Voxel (i, j, k) has its centre at origin + direction @ (spacing * (i, j, k)), in mm. "
                      "`data` is a read-only (nx, ny, nz) view (Fortran order: i fastest, as stored).")
                      .c_str())
      .def(py::init([](py::handle data, py::handle spacing, py::handle origin, py::handle direction) {
             const std::string expected = "a 3-D integer array of shape (nx, ny, nz)";
             if (!py::isinstance<py::array>(data))
               throw InvalidInput(cat("data: expected ", expected, "; got ", describe_object(data)));
             auto a = py::reinterpret_borrow<py::array>(data);
             const char k = a.dtype().kind();
             if (a.ndim() != 3 || (k != 'i' && k != 'u' && k != 'b'))
               throw InvalidInput(cat("data: expected ", expected, "; got ", describe_object(data)));
             Vol v;
             for (int d = 0; d < 3; ++d) v.dims[d] = static_cast<Index>(a.shape(d));
             auto np = py::module_::import("numpy");
             auto i64 = py::array_t<std::int64_t>(np.attr("asfortranarray")(a, "dtype"_a = "int64"));
             const std::int64_t lo = std::numeric_limits<T>::min(), hi = std::numeric_limits<T>::max();
             v.data.resize(v.size());
             const std::int64_t* src = i64.data();
             for (std::size_t i = 0; i < v.data.size(); ++i) {
               if (src[i] < lo || src[i] > hi)
                 throw InvalidInput(cat("data: voxel ", i, " has value ", src[i], " outside the range [", lo,
                                        ", ", hi, "] of the volume type"));
               v.data[i] = static_cast<T>(src[i]);
             }
             v.spacing = vec3_arg(spacing, "spacing");
             for (int d = 0; d < 3; ++d) require_positive(v.spacing[d], "spacing[", d, "]");
             v.origin = vec3_arg(origin, "origin");
             v.direction = direction.is_none() ? Mat3(Mat3::Identity()) : mat3_arg(direction, "direction");
             return v;
           }),
           "data"_a, "spacing"_a = py::make_tuple(1.0, 1.0, 1.0), "origin"_a = py::make_tuple(0.0, 0.0, 0.0),
           "direction"_a = py::none(),
           "Builds a volume from a (nx, ny, nz) integer array (copied), spacing and origin in mm and a 3 x 3 "
           "direction matrix (columns: world directions of the i, j, k axes; None = identity).")
      .def_property_readonly(
          "data",
          [](py::object self) {
            const Vol& v = self.cast<const Vol&>();
            const py::ssize_t s = sizeof(T);
            py::array_t<T> a({static_cast<py::ssize_t>(v.dims[0]), static_cast<py::ssize_t>(v.dims[1]),
                              static_cast<py::ssize_t>(v.dims[2])},
                             {s, s * v.dims[0], s * v.dims[0] * v.dims[1]}, v.data.data(), self);
            py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
            return a;
          },
          "Voxel values as a read-only (nx, ny, nz) NumPy view (no copy).")
      .def_property_readonly(
          "dims", [](const Vol& v) { return py::make_tuple(v.dims[0], v.dims[1], v.dims[2]); },
          "(nx, ny, nz).")
      .def_property_readonly(
          "spacing", [](const Vol& v) { return copy_of(v.spacing); }, "Voxel spacing, mm.")
      .def_property_readonly(
          "origin", [](const Vol& v) { return copy_of(v.origin); }, "Centre of voxel (0, 0, 0), mm.")
      .def_property_readonly(
          "direction", [](const Vol& v) { return copy_of(v.direction); },
          "3 x 3 matrix whose columns are the world directions of the i, j, k axes.")
      .def_property_readonly("size", &Vol::size, "Number of voxels nx * ny * nz.")
      .def(
          "to_world",
          [](const Vol& v, py::handle ijk) { return copy_of(Vec3(v.to_world(vec3_arg(ijk, "ijk")))); },
          "ijk"_a, "World position (mm) of a continuous voxel coordinate (i, j, k).")
      .def(
          "to_index", [](const Vol& v, py::handle p) { return copy_of(Vec3(v.to_index(vec3_arg(p, "p")))); },
          "p"_a, "Continuous voxel coordinate of a world position p (mm).")
      .def("__repr__", [name](const Vol& v) {
        return cat("<medspring.", name, " ", v.dims[0], " x ", v.dims[1], " x ", v.dims[2], ", spacing (",
                   v.spacing[0], ", ", v.spacing[1], ", ", v.spacing[2], ") mm>");
      });
}

}  // namespace

void bind_geometry(py::module_& m) {
  // ---- SurfaceMesh ----
  py::class_<SurfaceMesh>(m, "SurfaceMesh",
                          "A triangle surface mesh in millimetres (immutable from Python).\n\n"
                          "V: (#V, 3) float64 vertex positions, mm; F: (#F, 3) int32 triangles (0-based, "
                          "counter-clockwise seen from outside). Both are read-only NumPy views (no copy); "
                          "build a new mesh to change them: SurfaceMesh(V2, mesh.F).")
      .def(py::init(&make_mesh), "V"_a, "F"_a,
           "Builds a mesh from V, a C-contiguous float64 array of shape (N, 3) in mm, and F, an integer "
           "array of shape (F, 3) with indices in [0, N). Both are copied. Raises InvalidInput (ValueError) "
           "for wrong shapes, dtypes, non-contiguous arrays, NaN or out-of-range indices.")
      .def_property_readonly(
          "V", [](py::object self) { return view_of(self.cast<const SurfaceMesh&>().V, self); },
          "Vertex positions, read-only (#V, 3) float64 view, mm.")
      .def_property_readonly(
          "F", [](py::object self) { return view_of(self.cast<const SurfaceMesh&>().F, self); },
          "Triangles, read-only (#F, 3) int32 view.")
      .def_property_readonly("num_vertices", &SurfaceMesh::num_vertices, "Number of vertices.")
      .def_property_readonly("num_faces", &SurfaceMesh::num_faces, "Number of triangles.")
      .def("validate", &validate_mesh, "Checks the mesh without modifying it; returns a MeshReport.")
      .def(py::pickle([](const SurfaceMesh& s) { return py::make_tuple(copy_of(s.V), copy_of(s.F)); },
                      [](py::tuple t) { return make_mesh(t[0], t[1]); }))
      .def("__repr__", [](const SurfaceMesh& s) {
        return cat("<medspring.SurfaceMesh ", s.num_vertices(), " vertices, ", s.num_faces(), " faces>");
      });

  py::class_<MeshReport>(
      m, "MeshReport", "What validate_mesh found. Counts are exact; first_problem names the first offender.")
      .def_readonly("vertices", &MeshReport::vertices, "Number of vertices.")
      .def_readonly("faces", &MeshReport::faces, "Number of triangles.")
      .def_readonly("edges", &MeshReport::edges, "Number of unique edges.")
      .def_readonly("nonfinite_vertices", &MeshReport::nonfinite_vertices, "Rows of V with NaN/Inf.")
      .def_readonly("bad_indices", &MeshReport::bad_indices, "Faces with an index outside [0, #V).")
      .def_readonly("degenerate_faces", &MeshReport::degenerate_faces, "Repeated index or zero area.")
      .def_readonly("duplicate_faces", &MeshReport::duplicate_faces, "Same vertex set as an earlier face.")
      .def_readonly("boundary_edges", &MeshReport::boundary_edges, "Edges with one incident face.")
      .def_readonly("nonmanifold_edges", &MeshReport::nonmanifold_edges, "Edges with more than two faces.")
      .def_readonly("inconsistent_edges", &MeshReport::inconsistent_edges,
                    "Interior edges traversed twice in the same direction.")
      .def_readonly("isolated_vertices", &MeshReport::isolated_vertices, "Vertices in no face.")
      .def_readonly("components", &MeshReport::components, "Connected components (by faces).")
      .def_readonly("euler_characteristic", &MeshReport::euler_characteristic, "V - E + F.")
      .def_readonly("bbox_diagonal", &MeshReport::bbox_diagonal, "Bounding-box diagonal, mm.")
      .def_readonly("signed_volume", &MeshReport::signed_volume, "mm^3, > 0 for outward normals (closed).")
      .def_readonly("first_problem", &MeshReport::first_problem, "e.g. 'face 17: index 5002 out of range'.")
      .def_property_readonly("closed", &MeshReport::closed, "No boundary edges.")
      .def_property_readonly("manifold", &MeshReport::manifold, "No non-manifold edges.")
      .def_property_readonly("valid", &MeshReport::valid,
                             "Usable for simulation: finite, valid indices, no degenerate, duplicate or "
                             "non-manifold faces (open boundaries allowed).")
      .def("summary", &MeshReport::summary, "One-line summary.")
      .def("__repr__", [](const MeshReport& r) { return "<medspring.MeshReport " + r.summary() + ">"; });

  m.def("validate_mesh", &validate_mesh, "mesh"_a,
        "Checks a mesh without modifying it; returns a MeshReport.");
  m.def(
      "require_valid_mesh",
      [](const SurfaceMesh& mesh, const std::string& what, bool closed, bool manifold) {
        return require_valid_mesh(mesh, what, {.closed = closed, .manifold = manifold});
      },
      "mesh"_a, "what"_a = "mesh", "closed"_a = false, "manifold"_a = true,
      "Raises InvalidInput('<what>: <first problem>') unless the mesh is valid (and closed / manifold if "
      "required); returns the MeshReport otherwise.");
  m.def(
      "weld_vertices",
      [](const SurfaceMesh& mesh, double tol) {
        SurfaceMesh out = mesh;
        std::vector<Index> old_to_new;
        const Index merged = weld_vertices(out, tol, &old_to_new);
        return py::make_tuple(std::move(out), merged, copy_of(old_to_new));
      },
      "mesh"_a, "tol"_a = -1.0,
      "Merges vertices closer than tol (mm; default 1e-9 x bounding-box diagonal), drops faces that become "
      "degenerate and unreferenced vertices. Returns (welded_mesh, merged_count, old_to_new) where "
      "old_to_new[i] is the new index of old vertex i (-1 if removed).");
  m.def(
      "vertex_normals",
      [](const SurfaceMesh& mesh) {
        MatX3 N;
        vertex_normals(mesh.V, mesh.F, N);
        return copy_of(N);
      },
      "mesh"_a, "Area-weighted unit vertex normals (#V, 3) of a mesh.");
  m.def(
      "vertex_normals",
      [](py::handle V, py::handle F) {
        const SurfaceMesh mesh = make_mesh(V, F);
        MatX3 N;
        vertex_normals(mesh.V, mesh.F, N);
        return copy_of(N);
      },
      "V"_a, "F"_a,
      "Area-weighted unit vertex normals (#V, 3) of positions V (N, 3) over triangles F (F, 3).");
  m.def(
      "face_normals", [](const SurfaceMesh& mesh) { return copy_of(face_normals(mesh.V, mesh.F)); }, "mesh"_a,
      "Unit face normals (#F, 3).");
  m.def(
      "face_normals",
      [](py::handle V, py::handle F) {
        const SurfaceMesh mesh = make_mesh(V, F);
        return copy_of(face_normals(mesh.V, mesh.F));
      },
      "V"_a, "F"_a, "Unit face normals (#F, 3) of positions V over triangles F.");
  m.def(
      "signed_volume", [](const SurfaceMesh& mesh) { return signed_volume(mesh.V, mesh.F); }, "mesh"_a,
      "Signed enclosed volume (divergence theorem), mm^3.");
  m.def(
      "signed_volume",
      [](py::handle V, py::handle F) {
        const SurfaceMesh mesh = make_mesh(V, F);
        return signed_volume(mesh.V, mesh.F);
      },
      "V"_a, "F"_a, "Signed enclosed volume of positions V over triangles F, mm^3.");
  m.def(
      "surface_area", [](const SurfaceMesh& mesh) { return surface_area(mesh.V, mesh.F); }, "mesh"_a,
      "Total area, mm^2.");
  m.def(
      "bounds",
      [](py::handle V) {
        const MatX3 P = points_arg(V, "V");
        require(P.rows() > 0, "V: expected at least one point");
        const Eigen::Matrix<double, 2, 3, Eigen::RowMajor> b = bounds(P);
        py::array_t<double> a({2, 3});
        for (int r = 0; r < 2; ++r)
          for (int c = 0; c < 3; ++c) a.mutable_at(r, c) = b(r, c);
        return a;
      },
      "V"_a, "Axis-aligned bounds of points V (N, 3) as a (2, 3) array: min row, max row.");

  // ---- Phantoms ----
  m.def("tube", &tube, "rings"_a = 40, "spokes"_a = 30, "spacing"_a = 2.5, "radius"_a = 3.0,
        "A straight open circular tube along +x: `rings` rings spaced `spacing` mm, `spokes` nodes per ring "
        "on radius `radius` mm (node i * spokes + j). tube() is the paper's 40 x 30 vessel surface "
        "(1200 nodes, 3540 springs).");
  m.def(
      "tube_grid_faces", [](Index rings, Index spokes) { return copy_of(tube_grid_faces(rings, spokes)); },
      "rings"_a, "spokes"_a, "Triangles (2 M (n - 1), 3) of the structured tube grid of n rings x M spokes.");
  m.def("kidney_phantom", &kidney_phantom,
        "The 458-node latitude-longitude kidney phantom (ALGORITHMS.md §1.1): ellipsoid (55, 28, 18) mm bent "
        "with radius 90 mm; 1368 edges, 912 triangles, closed.");
  m.def(
      "kidney_bend",
      [](py::handle q, double bend_radius) {
        return copy_of(Vec3(kidney_bend(vec3_arg(q, "q"), bend_radius)));
      },
      "q"_a, "bend_radius"_a = 90.0, "The bend map B(q) of the kidney phantom (§1.1), mm.");
  m.def("icosphere", &icosphere, "subdivisions"_a = 2, "radius"_a = 10.0,
        "A closed icosphere of the given radius (mm) after `subdivisions` midpoint subdivisions "
        "(10 * 4^s + 2 vertices).");

  // ---- Topology ----
  m.def(
      "unique_edges", [](py::handle F) { return copy_of(unique_edges(faces_arg(F, "F"))); }, "F"_a,
      "Unique undirected edges (E, 2) with i < j of a triangle list, sorted lexicographically (D-1).");
  py::class_<Adjacency>(m, "Adjacency",
                        "Compressed sparse row adjacency: the neighbours of node i are "
                        "neighbors[offsets[i]:offsets[i + 1]], sorted ascending.")
      .def_property_readonly(
          "offsets", [](py::object self) { return view_of(self.cast<const Adjacency&>().offsets, self); },
          "(#N + 1,) int32 read-only view.")
      .def_property_readonly(
          "neighbors", [](py::object self) { return view_of(self.cast<const Adjacency&>().neighbors, self); },
          "(2 #E,) int32 read-only view.")
      .def_property_readonly("num_nodes", &Adjacency::num_nodes, "Number of nodes.")
      .def(
          "degree",
          [](const Adjacency& a, Index i) {
            require_index(i, a.num_nodes(), "node");
            return a.degree(i);
          },
          "i"_a, "Number of neighbours of node i.")
      .def(
          "neighbors_of",
          [](const Adjacency& a, Index i) {
            require_index(i, a.num_nodes(), "node");
            return copy_of(std::vector<Index>(a.begin(i), a.end(i)));
          },
          "i"_a, "The neighbours of node i (sorted).")
      .def("__repr__",
           [](const Adjacency& a) { return cat("<medspring.Adjacency ", a.num_nodes(), " nodes>"); });
  m.def(
      "vertex_adjacency",
      [](Index n, py::handle edges) { return vertex_adjacency(n, edges_arg(edges, "edges", n)); }, "n"_a,
      "edges"_a, "The CSR adjacency of n nodes from an (E, 2) edge list (duplicates merged).");
  m.def(
      "vertex_adjacency",
      [](const SurfaceMesh& mesh) { return vertex_adjacency(mesh.num_vertices(), unique_edges(mesh.F)); },
      "mesh"_a, "The CSR adjacency of a mesh's vertices over its unique edges.");
  m.def(
      "k_ring",
      [](const Adjacency& adj, Index c, int k) {
        require_index(c, adj.num_nodes(), "c");
        require(k >= 0, "k: must be >= 0 (got ", k, ")");
        return copy_of(k_ring(adj, c, k));
      },
      "adj"_a, "c"_a, "k"_a,
      "Nodes within k edge hops of c (including c), ordered by (hop distance, index).");
  m.def(
      "hop_distances",
      [](const Adjacency& adj, Index c) {
        require_index(c, adj.num_nodes(), "c");
        std::vector<int> d = hop_distances(adj, c);
        return copy_of(d);
      },
      "adj"_a, "c"_a, "Hop distance from c to every node (-1 if unreachable).");
  m.def(
      "bfs_patch",
      [](const Adjacency& adj, py::handle X0, Index c, Index count) {
        return copy_of(bfs_patch(adj, points_arg(X0, "X0", adj.num_nodes()), c, count));
      },
      "adj"_a, "X0"_a, "c"_a, "count"_a,
      "The first `count` nodes in breadth-first order from c, ordered by (hop distance, rest distance to c, "
      "index) (§6.1).");
  m.def(
      "valence_histogram", [](const Adjacency& adj) { return copy_of(valence_histogram(adj)); }, "adj"_a,
      "result[d] = number of nodes with d neighbours.");

  // ---- Centerlines ----
  py::class_<Centerline>(m, "Centerline",
                         "One centerline polyline in mm with the lumen radius at every point (immutable). "
                         "points: read-only (P, 3) view; radii: read-only (P,) view.")
      .def(py::init([](py::handle points, py::handle radii, std::string name) {
             Centerline c;
             c.points = points_arg(points, "points");
             c.radii = vector_arg(radii, "radii", static_cast<Index>(c.points.rows()), "P");
             for (Index i = 0; i < c.radii.size(); ++i) require_positive(c.radii[i], "radii[", i, "]");
             c.name = std::move(name);
             return c;
           }),
           "points"_a, "radii"_a, "name"_a = "",
           "A centerline from points (P, 3) in mm and radii (P,) in mm (> 0).")
      .def_property_readonly(
          "points", [](py::object self) { return view_of(self.cast<const Centerline&>().points, self); },
          "(P, 3) read-only view, mm.")
      .def_property_readonly(
          "radii", [](py::object self) { return view_of(self.cast<const Centerline&>().radii, self); },
          "(P,) read-only view, mm.")
      .def_readonly("name", &Centerline::name, "Name, e.g. 'line 0'.")
      .def("__len__", &Centerline::size)
      .def_property_readonly("size", &Centerline::size, "Number of points.")
      .def(
          "arc_length", [](const Centerline& c) { return copy_of(c.arc_length()); },
          "Cumulative arc length at every point (first = 0), mm.")
      .def("length", &Centerline::length, "Total length, mm.")
      .def("__repr__", [](const Centerline& c) {
        return cat("<medspring.Centerline '", c.name, "' ", c.size(), " points, ",
                   c.size() > 1 ? c.length() : 0.0, " mm>");
      });
  m.def("deduplicate", &deduplicate, "line"_a, "tol"_a,
        "Removes consecutive points closer than tol (mm), keeping the first of each run.");
  m.def("resample", &resample, "line"_a, "count"_a,
        "Resamples to `count` points at equal arc-length spacing (both ends included), interpolating "
        "positions and radii linearly.");

  // ---- Volumes ----
  bind_volume<std::int32_t>(m, "LabelVolume", "int32 label");
  bind_volume<std::uint8_t>(m, "MaskVolume", "uint8 binary mask");
  m.def("select_label", &select_label, "labels"_a, "label"_a,
        "Binary mask (MaskVolume) of the voxels equal to `label` (or > 0 if label < 0).");
}

}  // namespace medspring::python
