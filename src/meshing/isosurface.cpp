#include "medspring/meshing/isosurface.hpp"

#include <vtkCellArray.h>
#include <vtkDiscreteFlyingEdges3D.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkImageGaussianSmooth.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkWindowedSincPolyDataFilter.h>

#include <algorithm>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

void check_volume(const MaskVolume& mask) {
  for (int a = 0; a < 3; ++a)
    require(mask.dims[a] > 0, "isosurface: mask dims[", a, "] must be > 0 (got ", mask.dims[a], ")");
  require(mask.data.size() == mask.size(), "isosurface: mask has ", mask.data.size(), " voxels but dims ",
          mask.dims[0], " x ", mask.dims[1], " x ", mask.dims[2], " need ", mask.size());
  for (int a = 0; a < 3; ++a) require_positive(mask.spacing[a], cat("isosurface: mask spacing[", a, "]"));
  require(mask.origin.allFinite(), "isosurface: mask origin must be finite");
  require(mask.direction.allFinite() && std::abs(mask.direction.determinant()) > 1e-9,
          "isosurface: mask direction matrix must be finite and invertible");
}

}  // namespace

SurfaceMesh isosurface(const MaskVolume& mask, const IsosurfaceSettings& settings) {
  check_volume(mask);
  require_nonnegative(settings.blur_sigma_voxels, "IsosurfaceSettings::blur_sigma_voxels");
  require(settings.smoothing_iterations >= 0, "IsosurfaceSettings::smoothing_iterations must be >= 0 (got ",
          settings.smoothing_iterations, ")");
  require(settings.pass_band > 0.0 && settings.pass_band <= 2.0,
          "IsosurfaceSettings::pass_band must be in (0, 2] (got ", settings.pass_band, ")");
  const auto foreground =
      std::count_if(mask.data.begin(), mask.data.end(), [](std::uint8_t v) { return v != 0; });
  require(foreground > 0, "isosurface: mask is empty (no nonzero voxel)");

  // The mask, padded with empty voxels so that objects touching the border are closed, in a frame
  // with the mask's spacing and no rotation: voxel (i,j,k) of the mask sits at spacing .* (i,j,k).
  const bool blur = settings.blur_sigma_voxels > 0.0;
  const int pad = blur ? static_cast<int>(std::ceil(3.0 * settings.blur_sigma_voxels)) + 2 : 2;
  const int nx = mask.dims[0] + 2 * pad, ny = mask.dims[1] + 2 * pad, nz = mask.dims[2] + 2 * pad;
  vtkNew<vtkImageData> image;
  image->SetDimensions(nx, ny, nz);
  image->SetSpacing(mask.spacing[0], mask.spacing[1], mask.spacing[2]);
  image->SetOrigin(-pad * mask.spacing[0], -pad * mask.spacing[1], -pad * mask.spacing[2]);
  vtkNew<vtkFloatArray> values;
  values->SetNumberOfTuples(static_cast<vtkIdType>(nx) * ny * nz);
  values->FillValue(0.0f);
  for (Index k = 0; k < mask.dims[2]; ++k)
    for (Index j = 0; j < mask.dims[1]; ++j)
      for (Index i = 0; i < mask.dims[0]; ++i)
        if (mask.at(i, j, k) != 0)
          values->SetValue(static_cast<vtkIdType>(i + pad) +
                               static_cast<vtkIdType>(nx) *
                                   (static_cast<vtkIdType>(j + pad) + static_cast<vtkIdType>(ny) * (k + pad)),
                           1.0f);
  values->SetName("mask");
  image->GetPointData()->SetScalars(values);

  vtkSmartPointer<vtkPolyData> surface;
  if (blur) {
    vtkNew<vtkImageGaussianSmooth> gauss;
    gauss->SetInputData(image);
    gauss->SetDimensionality(3);
    gauss->SetStandardDeviations(settings.blur_sigma_voxels, settings.blur_sigma_voxels,
                                 settings.blur_sigma_voxels);
    gauss->SetRadiusFactors(3.0, 3.0, 3.0);
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetInputConnection(gauss->GetOutputPort());
    fe->SetValue(0, 0.5);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    surface = fe->GetOutput();
  } else {
    vtkNew<vtkDiscreteFlyingEdges3D> fe;
    fe->SetInputData(image);
    fe->SetValue(0, 1.0);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    surface = fe->GetOutput();
  }
  require(surface->GetNumberOfPolys() > 0, "isosurface: no surface found in the mask");

  if (settings.smoothing_iterations > 0) {
    vtkNew<vtkWindowedSincPolyDataFilter> smooth;
    smooth->SetInputData(surface);
    smooth->SetNumberOfIterations(settings.smoothing_iterations);
    smooth->SetPassBand(settings.pass_band);
    smooth->BoundarySmoothingOff();
    smooth->FeatureEdgeSmoothingOff();
    smooth->NonManifoldSmoothingOn();
    smooth->NormalizeCoordinatesOn();
    smooth->Update();
    surface = smooth->GetOutput();
  }
  if (settings.largest_component) {
    vtkNew<vtkPolyDataConnectivityFilter> conn;
    conn->SetInputData(surface);
    conn->SetExtractionModeToLargestRegion();
    conn->Update();
    surface = conn->GetOutput();
  }
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputData(surface);
  tri->PassVertsOff();
  tri->PassLinesOff();
  tri->Update();
  surface = tri->GetOutput();

  // To world millimetres: x_world = origin + direction * (spacing .* ijk) = origin + direction * p.
  SurfaceMesh mesh;
  const vtkIdType np = surface->GetNumberOfPoints();
  mesh.V.resize(static_cast<Index>(np), 3);
  for (vtkIdType p = 0; p < np; ++p) {
    double x[3];
    surface->GetPoint(p, x);
    const Vec3 w = mask.origin + mask.direction * Vec3(x[0], x[1], x[2]);
    mesh.V.row(static_cast<Index>(p)) = w.transpose();
  }
  vtkCellArray* polys = surface->GetPolys();
  mesh.F.resize(static_cast<Index>(polys->GetNumberOfCells()), 3);
  vtkNew<vtkIdList> ids;
  Index f = 0;
  for (vtkIdType c = 0; c < polys->GetNumberOfCells(); ++c) {
    polys->GetCellAtId(c, ids);
    if (ids->GetNumberOfIds() != 3) continue;
    for (int k = 0; k < 3; ++k) mesh.F(f, k) = static_cast<Index>(ids->GetId(k));
    ++f;
  }
  mesh.F.conservativeResize(f, 3);
  weld_vertices(mesh);  // also drops the points the largest-component filter left unreferenced
  require(mesh.num_faces() > 0, "isosurface: no surface found in the mask");
  if (signed_volume(mesh.V, mesh.F) < 0.0) mesh.F.col(1).swap(mesh.F.col(2));  // outward
  return mesh;
}

}  // namespace medspring
