// Reads meshes through MedSpring::io: an OBJ written here (a unit tetrahedron in centimetres, scaled to
// mm on load) and a VTK XML file of the icosphere phantom written and read back by MedSpring (VTK).
// Exits non-zero on any mismatch.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <medspring/geometry/phantoms.hpp>
#include <medspring/io/mesh_io.hpp>
using namespace medspring;

int main(int argc, char** argv) {
  const std::filesystem::path dir = argc > 1 ? argv[1] : ".";
  const auto obj = dir / "tetra.obj";
  std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  const SurfaceMesh tetra = read_mesh(obj, {.unit = LengthUnit::Centimetre});
  const bool tetra_ok = tetra.num_vertices() == 4 && tetra.num_faces() == 4 &&
                        std::abs(tetra.V.col(0).maxCoeff() - 10.0) < 1e-12;  // 1 cm = 10 mm

  const SurfaceMesh sphere = icosphere(2, 10.0);
  const auto vtp = dir / "sphere.vtp";
  write_vtp(vtp, sphere);
  const MeshReadResult back = read_mesh_with_report(vtp);
  const bool sphere_ok = back.format == "VTP" && back.mesh.num_vertices() == sphere.num_vertices() &&
                         back.mesh.num_faces() == sphere.num_faces() &&
                         (back.mesh.V - sphere.V).cwiseAbs().maxCoeff() < 1e-9;
  std::printf("read_mesh: tetra.obj %lld vertices / %lld faces (x max %.1f mm), sphere.vtp %lld / %lld %s\n",
              static_cast<long long>(tetra.num_vertices()), static_cast<long long>(tetra.num_faces()),
              tetra.V.col(0).maxCoeff(), static_cast<long long>(back.mesh.num_vertices()),
              static_cast<long long>(back.mesh.num_faces()), back.format.c_str());
  return tetra_ok && sphere_ok ? 0 : 1;
}
