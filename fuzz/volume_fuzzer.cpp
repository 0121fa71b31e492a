// Fuzz target: read_label_volume (io/volume_io.hpp) on one volume format, chosen at link time by
// fuzz::kExtension (".nii", ".mha", ".nrrd"); a NIfTI input that starts with the gzip magic is
// written as ".nii.gz". Accepted: IoError / InvalidInput. A result must be a non-empty volume whose
// data size matches its dims, with finite positive spacing, a finite origin and an orthonormal
// direction.
#include <string>

#include "fuzz_support.hpp"
#include "medspring/core/check.hpp"
#include "medspring/io/volume_io.hpp"

using namespace medspring;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string ext = fuzz::kExtension;
  if (ext == ".nii" && size >= 2 && data[0] == 0x1f && data[1] == 0x8b) ext = ".nii.gz";
  const auto path = fuzz::write_scratch(data, size, ext);
  LabelVolume v;
  if (!fuzz::accepts([&] { v = read_label_volume(path); })) return 0;
  MEDSPRING_FUZZ_CHECK(v.dims[0] > 0 && v.dims[1] > 0 && v.dims[2] > 0,
                       cat(v.dims[0], " x ", v.dims[1], " x ", v.dims[2]));
  MEDSPRING_FUZZ_CHECK(v.data.size() == v.size(), cat(v.data.size(), " values"));
  MEDSPRING_FUZZ_CHECK(v.spacing.allFinite() && v.spacing.minCoeff() > 0, "spacing");
  MEDSPRING_FUZZ_CHECK(v.origin.allFinite(), "origin");
  MEDSPRING_FUZZ_CHECK(
      v.direction.allFinite() && (v.direction.transpose() * v.direction - Mat3::Identity()).norm() < 1e-3,
      "direction is not a rotation");
  return 0;
}
