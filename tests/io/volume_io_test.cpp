#include "medspring/io/volume_io.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "io_test_util.hpp"
#include "medspring/io/mesh_io.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;

// --- a minimal NIfTI-1 writer (field offsets of nifti1.h), to test the orientation maths on files
// --- whose header we control completely

struct NiftiSpec {
  std::array<short, 3> dims{3, 4, 5};
  short dim4 = 1;
  short datatype = 2;  // DT_UINT8
  short bitpix = 8;
  float pixdim[4] = {1, 1, 1, 1};  // pixdim[0] = qfac
  short qform_code = 0, sform_code = 0;
  float quatern[3] = {0, 0, 0}, qoffset[3] = {0, 0, 0};
  float srow[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  float slope = 0, inter = 0;
};

template <class T>
void put(std::string& buf, std::size_t offset, T value) {
  std::memcpy(buf.data() + offset, &value, sizeof(T));
}

/// Writes a .nii with the given header and raw voxel bytes (file order, x fastest).
void write_nifti(const fs::path& path, const NiftiSpec& s, const std::string& voxels) {
  std::string h(352, '\0');
  put<int>(h, 0, 348);
  put<short>(h, 40, s.dim4 > 1 ? 4 : 3);
  for (int a = 0; a < 3; ++a) put<short>(h, 42 + 2 * a, s.dims[a]);
  put<short>(h, 48, s.dim4);
  for (int a = 4; a < 7; ++a) put<short>(h, 42 + 2 * a, 1);
  put<short>(h, 70, s.datatype);
  put<short>(h, 72, s.bitpix);
  for (int a = 0; a < 4; ++a) put<float>(h, 76 + 4 * a, s.pixdim[a]);
  put<float>(h, 108, 352.0f);
  put<float>(h, 112, s.slope);
  put<float>(h, 116, s.inter);
  put<char>(h, 123, 2);  // xyzt_units: mm
  put<short>(h, 252, s.qform_code);
  put<short>(h, 254, s.sform_code);
  for (int a = 0; a < 3; ++a) {
    put<float>(h, 256 + 4 * a, s.quatern[a]);
    put<float>(h, 268 + 4 * a, s.qoffset[a]);
    for (int c = 0; c < 4; ++c) put<float>(h, 280 + 16 * a + 4 * c, s.srow[a][c]);
  }
  std::memcpy(h.data() + 344, "n+1", 4);
  testing::write_text(path, h + voxels);
}

/// uint8 voxels of a 3x4x5 volume, all zero but file voxel (1, 2, 3) = 7.
std::string marked_voxels(const NiftiSpec& s) {
  std::string v(static_cast<std::size_t>(s.dims[0] * s.dims[1] * s.dims[2]), '\0');
  v[static_cast<std::size_t>(1 + s.dims[0] * (2 + s.dims[1] * 3))] = 7;
  return v;
}

/// World position of the (single) voxel holding `label`.
Vec3 world_of_label(const LabelVolume& v, std::int32_t label) {
  Vec3 found = Vec3::Constant(std::nan(""));
  int n = 0;
  for (Index k = 0; k < v.dims[2]; ++k)
    for (Index j = 0; j < v.dims[1]; ++j)
      for (Index i = 0; i < v.dims[0]; ++i)
        if (v.at(i, j, k) == label) {
          found = v.to_world(Vec3(i, j, k));
          ++n;
        }
  EXPECT_EQ(n, 1);
  return found;
}

void expect_vec_near(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

// --- the real mask ------------------------------------------------------------------------------------

TEST(VolumeIo, AortaMaskHasTheDocumentedSizeSpacingAndForegroundCount) {
  const LabelVolume v = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  EXPECT_EQ(v.dims, (std::array<Index, 3>{120, 126, 164}));
  EXPECT_EQ(v.spacing, Vec3(1.5, 1.5, 1.5));
  std::size_t ones = 0, others = 0;
  for (const auto x : v.data) {
    if (x == 1)
      ++ones;
    else if (x != 0)
      ++others;
  }
  EXPECT_EQ(ones, 72810u);
  EXPECT_EQ(others, 0u);
  // sform (RAS): x and y axes point to -x and -y of the world
  EXPECT_LE((v.direction - Mat3(Vec3(-1, -1, 1).asDiagonal())).norm(), 1e-12);
  expect_vec_near(v.origin, Vec3(71.658203125, 255.658203125, 540.2000122070312), 1e-9);
}

TEST(VolumeIo, AortaMaskForegroundLinesUpWithTheAortaSurfaceInRasMillimetres) {
  const LabelVolume v = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  const SurfaceMesh aorta = read_mesh(testing::require_data_file("aorta_totalseg_ct.obj"));
  Vec3 lo = Vec3::Constant(1e300), hi = -lo;
  for (Index k = 0; k < v.dims[2]; ++k)
    for (Index j = 0; j < v.dims[1]; ++j)
      for (Index i = 0; i < v.dims[0]; ++i)
        if (v.at(i, j, k) != 0) {
          const Vec3 p = v.to_world(Vec3(i, j, k));
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
  const auto b = bounds(aorta.V);
  // The surface was cut at iso 0.5 of the blurred mask: each face of its box lies within one voxel
  // (1.5 mm) of the box of the foreground voxel centres.
  expect_vec_near(lo, b.row(0).transpose(), 1.5);
  expect_vec_near(hi, b.row(1).transpose(), 1.5);
}

TEST(VolumeIo, AortaMaskRoundTripsThroughMetaImage) {
  const LabelVolume v = read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  const fs::path file = testing::temp_dir("vol-rt") / "aorta.mha";
  write_label_volume(file, v);
  const LabelVolume back = read_label_volume(file);
  EXPECT_EQ(back.dims, v.dims);
  EXPECT_EQ(back.data, v.data);
  EXPECT_EQ(back.spacing, v.spacing);
  expect_vec_near(back.origin, v.origin, 1e-9);
  EXPECT_LE((back.direction - v.direction).norm(), 1e-12);
}

// --- MetaImage ----------------------------------------------------------------------------------------

LabelVolume oblique_volume(std::int32_t big_label) {
  LabelVolume v;
  v.dims = {5, 4, 3};
  v.spacing = Vec3(0.5, 0.75, 2.0);
  v.origin = Vec3(10.0, -20.0, 30.0);
  v.direction = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  v.data.resize(v.size());
  for (std::size_t i = 0; i < v.data.size(); ++i) v.data[i] = static_cast<std::int32_t>(i % 7);
  v.at(4, 3, 2) = big_label;
  v.at(0, 1, 2) = -3;
  return v;
}

TEST(VolumeIo, MetaImageRoundTripKeepsLabelsAndObliqueGeometry) {
  const fs::path dir = testing::temp_dir("vol-mha");
  for (const std::int32_t big : {9, 300, 100000}) {  // stored as uchar... short / int
    SCOPED_TRACE(big);
    LabelVolume v = oblique_volume(big);
    if (big == 9) v.at(0, 1, 2) = 0;  // non-negative: uchar
    write_label_volume(dir / "v.mha", v);
    const LabelVolume back = read_label_volume(dir / "v.mha");
    EXPECT_EQ(back.dims, v.dims);
    EXPECT_EQ(back.data, v.data);
    EXPECT_LE((back.spacing - v.spacing).norm(), 1e-12);
    expect_vec_near(back.origin, v.origin, 1e-9);
    EXPECT_LE((back.direction - v.direction).norm(), 1e-9);
    expect_vec_near(back.to_world(Vec3(4, 3, 2)), v.to_world(Vec3(4, 3, 2)), 1e-9);
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no temporaries
}

TEST(VolumeIo, MetaImageIsStoredInItksLpsFrame) {
  LabelVolume v;
  v.dims = {2, 2, 2};
  v.origin = Vec3(10, 20, 30);  // RAS
  v.data.assign(8, 1);
  const fs::path file = testing::temp_dir("vol-lps") / "v.mha";
  write_label_volume(file, v);
  const std::string text = testing::read_text(file);
  EXPECT_NE(text.find("Offset = -10 -20 30"), std::string::npos) << text.substr(0, 400);
  EXPECT_NE(text.find("TransformMatrix = -1 0 0 0 -1 0 0 0 1"), std::string::npos) << text.substr(0, 400);
}

// --- NIfTI orientation ----------------------------------------------------------------------------------

TEST(VolumeIo, NiftiQformWithNegativeQfacMapsVoxelsLikeTheNiftiAffine) {
  NiftiSpec s;
  s.pixdim[0] = -1;  // qfac: left-handed voxel axes, VTK reverses the slices
  s.pixdim[1] = 2;
  s.pixdim[2] = 3;
  s.pixdim[3] = 4;
  s.qform_code = 1;
  s.qoffset[0] = 10;
  s.qoffset[1] = 20;
  s.qoffset[2] = 30;
  const fs::path file = testing::temp_dir("vol-qfac") / "q.nii";
  write_nifti(file, s, marked_voxels(s));
  const LabelVolume v = read_label_volume(file);
  // file voxel (1, 2, 3): (10 + 2*1, 20 + 3*2, 30 - 4*3)
  expect_vec_near(world_of_label(v, 7), Vec3(12, 26, 18), 1e-5);
  EXPECT_LE((v.spacing - Vec3(2, 3, 4)).norm(), 1e-6);
}

TEST(VolumeIo, NiftiRotatedQformMapsVoxelsLikeTheNiftiAffine) {
  NiftiSpec s;
  s.pixdim[1] = 2;
  s.pixdim[2] = 3;
  s.pixdim[3] = 4;
  s.qform_code = 1;
  // 90 degrees about z: quaternion (a, b, c, d) = (cos 45, 0, 0, sin 45)
  s.quatern[2] = static_cast<float>(std::sqrt(0.5));
  s.qoffset[0] = 1;
  const fs::path file = testing::temp_dir("vol-qrot") / "q.nii";
  write_nifti(file, s, marked_voxels(s));
  const LabelVolume v = read_label_volume(file);
  // R = [[0,-1,0],[1,0,0],[0,0,1]]: (1,0,0) + R * (2*1, 3*2, 4*3) = (1 - 6, 2, 12)
  expect_vec_near(world_of_label(v, 7), Vec3(-5, 2, 12), 1e-5);
}

TEST(VolumeIo, NiftiSformTakesPrecedenceOverQform) {
  NiftiSpec s;
  s.qform_code = 1;
  s.qoffset[0] = 1000;  // must be ignored
  s.sform_code = 2;
  const float srow[3][4] = {{0, 0, -2, 5}, {1.5, 0, 0, -7}, {0, 3, 0, 11}};
  std::memcpy(s.srow, srow, sizeof srow);
  const fs::path file = testing::temp_dir("vol-sform") / "s.nii";
  write_nifti(file, s, marked_voxels(s));
  const LabelVolume v = read_label_volume(file);
  // (5 - 2*3, -7 + 1.5*1, 11 + 3*2)
  expect_vec_near(world_of_label(v, 7), Vec3(-1, -5.5, 17), 1e-5);
  EXPECT_LE((v.spacing - Vec3(1.5, 3, 2)).norm(), 1e-6);
}

TEST(VolumeIo, NiftiWithoutOrientationUsesSpacingOnly) {
  NiftiSpec s;
  s.pixdim[1] = 0.5;
  s.pixdim[2] = 0.5;
  s.pixdim[3] = 2;
  const fs::path file = testing::temp_dir("vol-m1") / "m.nii";
  write_nifti(file, s, marked_voxels(s));
  expect_vec_near(world_of_label(read_label_volume(file), 7), Vec3(0.5, 1.0, 6.0), 1e-6);
}

// --- voxel types ----------------------------------------------------------------------------------------

TEST(VolumeIo, FloatVoxelsMustBeIntegersUnlessAThresholdIsGiven) {
  NiftiSpec s;
  s.datatype = 16;  // DT_FLOAT32
  s.bitpix = 32;
  std::vector<float> values(60, 0.0f);
  values[7] = 2.0f;
  std::string bytes(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  const fs::path dir = testing::temp_dir("vol-float");
  write_nifti(dir / "int.nii", s, bytes);
  const LabelVolume v = read_label_volume(dir / "int.nii");
  EXPECT_EQ(v.data[7], 2);

  values[7] = 0.75f;
  values[8] = 0.25f;
  bytes.assign(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  write_nifti(dir / "prob.nii", s, bytes);
  expect_error_naming([&] { read_label_volume(dir / "prob.nii"); }, "prob.nii: voxel (1, 2, 0): value 0.75");
  const LabelVolume b = read_label_volume(dir / "prob.nii", {.threshold = 0.5});
  EXPECT_EQ(b.data[7], 1);
  EXPECT_EQ(b.data[8], 0);
}

TEST(VolumeIo, NiftiSlopeAndInterceptAreApplied) {
  NiftiSpec s;
  s.slope = 2;
  s.inter = 1;
  const fs::path file = testing::temp_dir("vol-slope") / "s.nii";
  write_nifti(file, s, marked_voxels(s));
  const LabelVolume v = read_label_volume(file);
  EXPECT_EQ(v.at(1, 2, 3), 15);
  EXPECT_EQ(v.at(0, 0, 0), 1);
}

// --- NRRD ----------------------------------------------------------------------------------------------

TEST(VolumeIo, NrrdSpaceDirectionsInLpsAreConvertedToRas) {
  std::string voxels(60, '\0');
  voxels[1 + 3 * (2 + 4 * 3)] = 7;  // voxel (1, 2, 3) of 3 x 4 x 5
  const fs::path file = testing::temp_dir("vol-nrrd") / "v.nrrd";
  testing::write_text(file,
                      "NRRD0004\n# a comment\ntype: uint8\ndimension: 3\nspace: left-posterior-superior\n"
                      "sizes: 3 4 5\nspace directions: (0,2,0) (-1.5,0,0) (0,0,3)\nspace origin: (10,20,30)\n"
                      "kinds: domain domain domain\nendian: little\nencoding: raw\n\n" +
                          voxels);
  const LabelVolume v = read_label_volume(file);
  EXPECT_EQ(v.dims, (std::array<Index, 3>{3, 4, 5}));
  // LPS: (10, 20, 30) + 1*(0,2,0) + 2*(-1.5,0,0) + 3*(0,0,3) = (7, 22, 39) -> RAS (-7, -22, 39)
  expect_vec_near(world_of_label(v, 7), Vec3(-7, -22, 39), 1e-9);
  EXPECT_LE((v.spacing - Vec3(2, 1.5, 3)).norm(), 1e-12);
}

TEST(VolumeIo, NrrdInRasWithoutDirectionsUsesSpacingsAndOrigin) {
  std::string voxels(12 * 3 * 2 * 2, '\0');     // int16, little-endian
  const std::size_t i = 11 + 12 * (1 + 3 * 1);  // voxel (11, 1, 1)
  voxels[2 * i] = static_cast<char>(0x2c);      // 300 = 0x012c
  voxels[2 * i + 1] = 0x01;
  const fs::path file = testing::temp_dir("vol-nrrd-ras") / "v.nrrd";
  testing::write_text(file,
                      "NRRD0004\ntype: short\ndimension: 3\nspace: right-anterior-superior\nsizes: 12 3 2\n"
                      "space directions: (0.5,0,0) (0,0.5,0) (0,0,2)\nspace origin: (1,2,3)\n"
                      "endian: little\nencoding: raw\n\n" +
                          voxels);
  const LabelVolume v = read_label_volume(file);
  EXPECT_EQ(v.dims, (std::array<Index, 3>{12, 3, 2}));
  expect_vec_near(world_of_label(v, 300), Vec3(1 + 5.5, 2 + 0.5, 3 + 2), 1e-12);
}

TEST(VolumeIo, NrrdInLeftAnteriorSuperiorSpaceIsRejected) {
  const fs::path file = testing::temp_dir("vol-nrrd-las") / "v.nrrd";
  testing::write_text(file,
                      "NRRD0004\ntype: uint8\ndimension: 3\nspace: left-anterior-superior\nsizes: 10 1 1\n"
                      "encoding: raw\n\n" +
                          std::string(10, '\0'));
  expect_error_naming([&] { read_label_volume(file); }, "v.nrrd: NRRD space 'left-anterior-superior'");
}

// --- malformed input ----------------------------------------------------------------------------------

TEST(VolumeIo, MissingEmptyGarbageAndUnsupportedFilesAreNamed) {
  const fs::path dir = testing::temp_dir("vol-bad");
  expect_error_naming([&] { read_label_volume(dir / "none.nii.gz"); }, "none.nii.gz: no such file");
  testing::write_text(dir / "mask.png", "\x89PNG");
  expect_error_naming([&] { read_label_volume(dir / "mask.png"); },
                      "mask.png: unknown volume file extension '.png'");
  testing::write_text(dir / "empty.nii", "");
  expect_error_naming([&] { read_label_volume(dir / "empty.nii"); }, "empty.nii: file is empty");
  std::string garbage(2000, '\0');
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<char>((i * 7919) % 251);
  for (const char* name : {"garbage.nii", "garbage.nii.gz", "garbage.mha", "garbage.nrrd"}) {
    testing::write_text(dir / name, garbage);
    expect_error_naming([&] { read_label_volume(dir / name); }, name);
  }
  // truncated compressed MetaImage (vtkMetaImageReader accepted it; MedSpring's reader counts the bytes)
  write_label_volume(dir / "whole.mha",
                     read_label_volume(testing::require_data_file("aorta_totalseg_mask.nii.gz")));
  const std::string mha = testing::read_text(dir / "whole.mha");
  testing::write_text(dir / "cut.mha", mha.substr(0, mha.size() - 5000));
  expect_error_naming([&] { read_label_volume(dir / "cut.mha"); }, "cut.mha: MetaImage: truncated data");
  testing::write_text(dir / "nodata.mhd",
                      "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
                      "ElementDataFile = missing.raw\n");
  expect_error_naming([&] { read_label_volume(dir / "nodata.mhd"); }, "nodata.mhd");
  // a truncated .nii.gz
  const std::string gz = testing::read_text(testing::require_data_file("aorta_totalseg_mask.nii.gz"));
  testing::write_text(dir / "cut.nii.gz", gz.substr(0, gz.size() / 2));
  expect_error_naming([&] { read_label_volume(dir / "cut.nii.gz"); },
                      "cut.nii.gz: NIfTI file is truncated");
  // a valid header announcing more voxels than the file holds
  NiftiSpec s;
  write_nifti(dir / "short.nii", s, std::string(10, '\0'));
  expect_error_naming([&] { read_label_volume(dir / "short.nii"); }, "short.nii");
  // 4-D
  s.dim4 = 2;
  write_nifti(dir / "four.nii", s, std::string(120, '\0'));
  expect_error_naming([&] { read_label_volume(dir / "four.nii"); }, "four.nii: 4-D image");
  // writing only .mha
  LabelVolume v;
  v.dims = {1, 1, 1};
  v.data = {1};
  expect_error_naming([&] { write_label_volume(dir / "out.nii", v); },
                      "out.nii: label volumes are written as");
  expect_error_naming([&] { write_label_volume(dir / "nofolder" / "out.mha", v); }, "does not exist");
}

}  // namespace
}  // namespace medspring
