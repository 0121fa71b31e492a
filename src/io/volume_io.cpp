#include "medspring/io/volume_io.hpp"

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkNIFTIImageHeader.h>
#include <vtkNIFTIImageReader.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSetGet.h>
#include <vtkmetaio/metaImage.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <type_traits>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "safe_readers.hpp"
#include "vtk_support.hpp"

namespace fs = std::filesystem;

namespace medspring {

using namespace io_detail;

namespace {

/// Captures what a library writes to std::cerr (vtkmetaio reports its errors there). Not thread-safe:
/// std::cerr is process-wide.
class CerrCapture {
 public:
  CerrCapture() : old_(std::cerr.rdbuf(buffer_.rdbuf())) {}
  ~CerrCapture() { std::cerr.rdbuf(old_); }
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  /// First non-empty line written so far ("" if none).
  std::string first_line() const {
    std::istringstream in(buffer_.str());
    std::string line;
    while (std::getline(in, line))
      if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
    return {};
  }

 private:
  std::ostringstream buffer_;
  std::streambuf* old_;
};

/// Voxel-to-world geometry: world = origin + direction * (spacing .* ijk).
struct Geometry {
  Vec3 spacing = Vec3::Ones();
  Vec3 origin = Vec3::Zero();
  Mat3 direction = Mat3::Identity();
};

/// Splits the linear part A (columns: world step of one voxel along i, j, k) into spacing (column
/// norms) and unit directions. A sheared A (non-orthogonal columns) is replaced by the nearest
/// orthogonal direction matrix (polar factor), keeping the column norms as spacing.
Geometry geometry_from_affine(const Mat3& A, const Vec3& t, const fs::path& path) {
  Geometry g;
  g.origin = t;
  for (int c = 0; c < 3; ++c) {
    g.spacing(c) = A.col(c).norm();
    if (!(std::isfinite(g.spacing(c)) && g.spacing(c) > 0))
      throw IoError(
          cat(name_of(path), ": voxel axis ", c, " has zero or non-finite length in the orientation matrix"));
    g.direction.col(c) = A.col(c) / g.spacing(c);
  }
  if (!t.allFinite()) throw IoError(cat(name_of(path), ": the volume origin is not finite"));
  if ((g.direction.transpose() * g.direction - Mat3::Identity()).norm() > 1e-4) {
    Eigen::JacobiSVD<Mat3> svd(g.direction, Eigen::ComputeFullU | Eigen::ComputeFullV);
    g.direction = svd.matrixU() * svd.matrixV().transpose();
  }
  return g;
}

std::string voxel_name(std::size_t i, const std::array<Index, 3>& dims) {
  const auto nx = static_cast<std::size_t>(dims[0]), ny = static_cast<std::size_t>(dims[1]);
  return cat("voxel (", i % nx, ", ", (i / nx) % ny, ", ", i / (nx * ny), ")");
}

/// Converts n voxels of type T to int32 labels: value = x * slope + inter when `scaled`; binarised
/// at `threshold` when it is not NaN; otherwise values must be integers that fit in int32.
template <class T>
void convert_voxels(const T* src, std::size_t n, bool scaled, double slope, double inter, double threshold,
                    const std::array<Index, 3>& dims, const fs::path& path, std::vector<std::int32_t>& out) {
  out.resize(n);
  constexpr double lo = std::numeric_limits<std::int32_t>::min(),
                   hi = std::numeric_limits<std::int32_t>::max();
  const bool binarise = !std::isnan(threshold);
  if constexpr (std::is_integral_v<T>) {
    if (!scaled && !binarise) {
      for (std::size_t i = 0; i < n; ++i) {
        if constexpr (static_cast<long double>(std::numeric_limits<T>::max()) > hi ||
                      static_cast<long double>(std::numeric_limits<T>::min()) < lo) {
          const auto x = static_cast<long double>(src[i]);
          if (x < lo || x > hi)
            throw IoError(cat(name_of(path), ": ", voxel_name(i, dims), ": label ", static_cast<double>(x),
                              " does not fit in int32"));
        }
        out[i] = static_cast<std::int32_t>(src[i]);
      }
      return;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double v = scaled ? static_cast<double>(src[i]) * slope + inter : static_cast<double>(src[i]);
    if (binarise) {
      out[i] = v >= threshold ? 1 : 0;
      continue;
    }
    const double r = std::nearbyint(v);
    if (!std::isfinite(v) || std::abs(v - r) > 1e-6)
      throw IoError(cat(name_of(path), ": ", voxel_name(i, dims), ": value ", v,
                        " is not an integer label (set ReadVolumeOptions::threshold to binarise)"));
    if (r < lo || r > hi)
      throw IoError(cat(name_of(path), ": ", voxel_name(i, dims), ": label ", r, " does not fit in int32"));
    out[i] = static_cast<std::int32_t>(r);
  }
}

/// Copies a single-component VTK image into a LabelVolume with the given geometry. `dims` overrides
/// the image's dimensions when VTK took the first axis for vector components (vtkNrrdReader does
/// so when it has <= 9 samples): the memory layout is the same, x fastest.
LabelVolume to_label_volume(vtkImageData* image, const Geometry& g, bool scaled, double slope, double inter,
                            const ReadVolumeOptions& options, const fs::path& path,
                            const std::array<Index, 3>* dims = nullptr) {
  LabelVolume vol;
  int d[3];
  image->GetDimensions(d);
  vol.dims = dims ? *dims : std::array<Index, 3>{d[0], d[1], d[2]};
  if (vol.dims[0] <= 0 || vol.dims[1] <= 0 || vol.dims[2] <= 0)
    throw IoError(cat(name_of(path), ": empty volume (", vol.dims[0], " x ", vol.dims[1], " x ", vol.dims[2],
                      " voxels)"));
  vtkDataArray* scalars = image->GetPointData() ? image->GetPointData()->GetScalars() : nullptr;
  if (!scalars) throw IoError(cat(name_of(path), ": the image has no voxel values"));
  const int components = dims ? 1 : scalars->GetNumberOfComponents();
  if (components != 1)
    throw IoError(cat(name_of(path), ": ", components, " components per voxel; a label volume needs 1"));
  const auto values = static_cast<std::size_t>(scalars->GetNumberOfTuples()) *
                      static_cast<std::size_t>(scalars->GetNumberOfComponents());
  if (values != vol.size())
    throw IoError(cat(name_of(path), ": ", values, " voxel values for ", vol.dims[0], " x ", vol.dims[1],
                      " x ", vol.dims[2], " voxels"));
  vol.spacing = g.spacing;
  vol.origin = g.origin;
  vol.direction = g.direction;
  switch (scalars->GetDataType()) {
    vtkTemplateMacro(convert_voxels(static_cast<const VTK_TT*>(scalars->GetVoidPointer(0)), vol.size(),
                                    scaled, slope, inter, options.threshold, vol.dims, path, vol.data));
    default:
      throw IoError(cat(name_of(path), ": unsupported voxel type ", scalars->GetDataTypeAsString()));
  }
  return vol;
}

// --- NIfTI ------------------------------------------------------------------------------------------

/// Rotation of a NIfTI quaternion (b, c, d), a = sqrt(1 - b^2 - c^2 - d^2) (nifti1.h, method 2).
Mat3 nifti_quaternion_rotation(double b, double c, double d) {
  double a = 1.0 - (b * b + c * c + d * d);
  if (a < 1e-7) {  // 180-degree rotation: renormalise (b, c, d), a = 0
    const double s = 1.0 / std::sqrt(b * b + c * c + d * d);
    b *= s;
    c *= s;
    d *= s;
    a = 0.0;
  } else {
    a = std::sqrt(a);
  }
  Mat3 R;
  R << a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c),  //
      2 * (b * c + a * d), a * a + c * c - b * b - d * d, 2 * (c * d - a * b),   //
      2 * (b * d - a * c), 2 * (c * d + a * b), a * a + d * d - c * c - b * b;
  return R;
}

LabelVolume read_nifti(const fs::path& path, const ReadVolumeOptions& options) {
  VtkMessageCapture capture;
  vtkNew<vtkNIFTIImageReader> reader;
  const std::string file = path.string();
  if (!guard_vtk(path, [&] { return reader->CanReadFile(file.c_str()); })) {
    capture.throw_if_failed(path);
    throw IoError(cat(name_of(path), ": not a NIfTI-1 or NIfTI-2 file (no valid header)"));
  }
  check_nifti(path);  // vtkNIFTIImageReader dereferences null on inconsistent headers
  reader->SetFileName(file.c_str());
  guard_vtk(path, [&] { reader->Update(); });
  capture.throw_if_failed(path, reader);
  vtkNIFTIImageHeader* h = reader->GetNIFTIHeader();
  if (!h) throw IoError(cat(name_of(path), ": no NIfTI header"));
  const auto ndim = h->GetDim(0);
  for (int a = 4; a <= std::min<int>(static_cast<int>(ndim), 7); ++a)
    if (h->GetDim(a) > 1)
      throw IoError(cat(name_of(path), ": ", ndim, "-D image (dim[", a, "] = ", h->GetDim(a),
                        "); a label volume is 3-D"));

  // Voxel (i, j, k) of the file -> world: A * (i, j, k) + t, in NIfTI's RAS+ frame.
  Mat3 A = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  auto pixdim = [&](int a) {
    const double p = h->GetPixDim(a);
    return p > 0 && std::isfinite(p) ? p : 1.0;
  };
  if (h->GetSFormCode() > 0) {  // method 3: sform rows
    double r[3][4];
    h->GetSRowX(r[0]);
    h->GetSRowY(r[1]);
    h->GetSRowZ(r[2]);
    for (int row = 0; row < 3; ++row) {
      for (int c = 0; c < 3; ++c) A(row, c) = r[row][c];
      t(row) = r[row][3];
    }
  } else if (h->GetQFormCode() > 0) {  // method 2: quaternion, pixdim, qfac = pixdim[0]
    const double qfac = h->GetPixDim(0) < 0 ? -1.0 : 1.0;
    A = nifti_quaternion_rotation(h->GetQuaternB(), h->GetQuaternC(), h->GetQuaternD()) *
        Vec3(pixdim(1), pixdim(2), qfac * pixdim(3)).asDiagonal();
    t = Vec3(h->GetQOffsetX(), h->GetQOffsetY(), h->GetQOffsetZ());
  } else {  // method 1 (Analyze): spacing only
    A = Vec3(pixdim(1), pixdim(2), pixdim(3)).asDiagonal();
  }
  // vtkNIFTIImageReader stores the slices in reverse order when qfac = -1: VTK's K = nz - 1 - k.
  vtkImageData* image = reader->GetOutput();
  int d[3];
  image->GetDimensions(d);
  if (reader->GetQFac() < 0) {
    t += (d[2] - 1) * A.col(2);
    A.col(2) = -A.col(2);
  }
  const Geometry g = geometry_from_affine(A, t, path);
  const double slope = h->GetSclSlope(), inter = h->GetSclInter();
  const bool scaled = std::isfinite(slope) && slope != 0.0 && (slope != 1.0 || inter != 0.0);
  return to_label_volume(image, g, scaled, slope, inter, options, path);
}

// --- MetaImage --------------------------------------------------------------------------------------

const Mat3 kLpsToRas = Vec3(-1.0, -1.0, 1.0).asDiagonal();  // also RAS -> LPS

LabelVolume read_metaimage(const fs::path& path, const ReadVolumeOptions& options) {
  // MedSpring's reader (safe_readers.hpp): metaio overflows a fixed buffer on a long header value.
  const RawVolume raw = read_metaimage_file(path);
  const Geometry g = geometry_from_affine(kLpsToRas * raw.axes * raw.spacing.asDiagonal(), kLpsToRas * raw.origin, path);
  return to_label_volume(raw.image, g, false, 1.0, 0.0, options, path);
}

// --- NRRD -------------------------------------------------------------------------------------------

/// The "key: value" fields of a NRRD header (keys lower-case), up to the blank line that ends it.
std::map<std::string, std::string> nrrd_fields(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::map<std::string, std::string> fields;
  std::string line;
  if (!std::getline(in, line) || line.rfind("NRRD", 0) != 0)
    throw IoError(cat(name_of(path), ": not a NRRD file (no NRRD magic)"));
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;
    if (line.front() == '#') continue;
    const auto colon = line.find(": ");
    if (colon == std::string::npos) continue;  // "key:=value" pairs are free-form metadata
    std::string key = line.substr(0, colon);
    std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
    fields[key] = line.substr(colon + 2);
  }
  return fields;
}

/// Parses "(a,b,c) (d,e,f) ..." into vectors; "none" entries are skipped.
std::vector<Vec3> nrrd_vectors(const std::string& text, const fs::path& path, const char* field) {
  std::vector<Vec3> out;
  std::size_t pos = 0;
  while ((pos = text.find('(', pos)) != std::string::npos) {
    const auto close = text.find(')', pos);
    if (close == std::string::npos) throw IoError(cat(name_of(path), ": malformed NRRD field '", field, "'"));
    std::string inner = text.substr(pos + 1, close - pos - 1);
    std::replace(inner.begin(), inner.end(), ',', ' ');
    std::istringstream in(inner);
    Vec3 v;
    if (!(in >> v(0) >> v(1) >> v(2)) || !v.allFinite())
      throw IoError(cat(name_of(path), ": malformed NRRD field '", field, "': '", text, "'"));
    out.push_back(v);
    pos = close + 1;
  }
  return out;
}

LabelVolume read_nrrd(const fs::path& path, const ReadVolumeOptions& options) {
  // The geometry (declared space, "space directions", "space origin", "spacings") comes from the
  // header fields; the voxels from MedSpring's reader.
  const auto fields = nrrd_fields(path);
  auto field = [&](const char* key) {
    const auto it = fields.find(key);
    return it == fields.end() ? std::string() : it->second;
  };
  std::string space = field("space");
  std::transform(space.begin(), space.end(), space.begin(), [](unsigned char c) { return std::tolower(c); });
  Vec3 flip = Vec3::Ones();  // to RAS
  if (space == "left-posterior-superior" || space == "lps") {
    flip = Vec3(-1, -1, 1);
  } else if (space == "left-anterior-superior" || space == "las" || space == "3d-left-handed") {
    // not converted (vtkNrrdReader, used before, reversed the rows of such files for raw encoding only)
    throw IoError(cat(name_of(path), ": NRRD space '", field("space"),
                      "' is not supported (store the volume in LPS or RAS)"));
  }

  // MedSpring's reader (safe_readers.hpp): vtkNrrdReader loops forever on a NUL in the header.
  const RawVolume raw = read_nrrd_file(path);
  Vec3 spacing = Vec3::Ones();
  if (const std::string sp = field("spacings"); !sp.empty()) {
    std::istringstream in(sp);
    for (int c = 0; c < raw.ndims; ++c) {
      double v = 1;
      if (!(in >> v) || !std::isfinite(v) || v <= 0) v = 1;  // "nan" for a non-spatial axis
      spacing(c) = v;
    }
  }
  Mat3 A = spacing.asDiagonal();
  Vec3 t = Vec3::Zero();
  if (const std::string dirs_text = field("space directions"); !dirs_text.empty()) {
    const auto dirs = nrrd_vectors(dirs_text, path, "space directions");
    if (dirs.size() != 3)
      throw IoError(
          cat(name_of(path), ": NRRD 'space directions' has ", dirs.size(), " spatial axes; expected 3"));
    for (int c = 0; c < 3; ++c) A.col(c) = dirs[static_cast<std::size_t>(c)];
  }
  if (const std::string o_text = field("space origin"); !o_text.empty()) {
    const auto o = nrrd_vectors(o_text, path, "space origin");
    if (o.size() != 1) throw IoError(cat(name_of(path), ": malformed NRRD field 'space origin'"));
    t = o[0];
  }
  const Geometry g = geometry_from_affine(flip.asDiagonal() * A, flip.asDiagonal() * t, path);

  return to_label_volume(raw.image, g, false, 1.0, 0.0, options, path);
}

template <class T>
std::vector<T> narrow_labels(const std::vector<std::int32_t>& data) {
  std::vector<T> out(data.size());
  std::transform(data.begin(), data.end(), out.begin(), [](std::int32_t v) { return static_cast<T>(v); });
  return out;
}

}  // namespace

LabelVolume read_label_volume(const fs::path& path, const ReadVolumeOptions& options) {
  const std::string ext = lower_extension(path);
  const bool nifti = ext == ".nii" || ext == ".nii.gz";
  const bool meta = ext == ".mha" || ext == ".mhd";
  const bool nrrd = ext == ".nrrd" || ext == ".nhdr";
  if (!nifti && !meta && !nrrd)
    throw IoError(cat(name_of(path), ": unknown volume file extension '", ext,
                      "' (expected .nii, .nii.gz, .mha, .mhd, .nrrd or .nhdr)"));
  if (require_input_file(path) == 0) throw IoError(cat(name_of(path), ": file is empty"));
  if (nifti) return read_nifti(path, options);
  if (meta) return read_metaimage(path, options);
  return read_nrrd(path, options);
}

void write_label_volume(const fs::path& path, const LabelVolume& volume) {
  const std::string ext = lower_extension(path);
  if (ext != ".mha")
    throw IoError(cat(name_of(path), ": label volumes are written as MetaImage .mha (got '", ext, "')"));
  for (int a = 0; a < 3; ++a) {
    require(volume.dims[a] > 0, "label volume: dims[", a, "] must be > 0 (got ", volume.dims[a], ")");
    require_positive(volume.spacing(a), cat("label volume: spacing[", a, "]"));
  }
  require(volume.data.size() == volume.size(), "label volume: ", volume.data.size(), " values for ",
          volume.dims[0], " x ", volume.dims[1], " x ", volume.dims[2], " voxels");
  require(volume.origin.allFinite() && volume.direction.allFinite(),
          "label volume: origin and direction must be finite");

  const auto [lo, hi] = std::minmax_element(volume.data.begin(), volume.data.end());
  std::vector<std::uint8_t> u8;
  std::vector<std::int16_t> i16;
  vtkmetaio::MET_ValueEnumType type = vtkmetaio::MET_INT;
  void* buffer = const_cast<std::int32_t*>(volume.data.data());  // metaio only reads it
  if (*lo >= 0 && *hi <= 255) {
    u8 = narrow_labels<std::uint8_t>(volume.data);
    type = vtkmetaio::MET_UCHAR;
    buffer = u8.data();
  } else if (*lo >= -32768 && *hi <= 32767) {
    i16 = narrow_labels<std::int16_t>(volume.data);
    type = vtkmetaio::MET_SHORT;
    buffer = i16.data();
  }
  const Vec3 origin = kLpsToRas * volume.origin;  // RAS -> LPS
  const Mat3 D = kLpsToRas * volume.direction;
  atomic_write(path, [&](const fs::path& tmp) {
    CerrCapture cerr;
    const int dims[3] = {volume.dims[0], volume.dims[1], volume.dims[2]};
    const double spacing[3] = {volume.spacing(0), volume.spacing(1), volume.spacing(2)};
    vtkmetaio::MetaImage meta(3, dims, spacing, type, 1, buffer);
    for (int i = 0; i < 3; ++i) {
      meta.Position(i, origin(i));
      for (int j = 0; j < 3; ++j) meta.TransformMatrix(i, j, D(j, i));  // row i = axis i (ITK)
    }
    meta.CompressedData(true);
    meta.ElementDataFileName("LOCAL");
    const std::string file = tmp.string();
    if (!meta.Write(file.c_str()))
      throw IoError(cat(name_of(path), ": MetaImage write failed ", cerr.first_line()));
  });
}

}  // namespace medspring
