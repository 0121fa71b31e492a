// Malformed VTK XML (.vtp) files (io/mesh_io.hpp): size headers and cell offsets beyond the data are
// refused before VTK allocates (every compressor and encoding), out-of-range indices and NaN points named.
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridWriter.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "io_test_util.hpp"
#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/io/mesh_io.hpp"
#include "mesh_io_test_util.hpp"
#include "test_support.hpp"

namespace medspring {
namespace {

namespace fs = std::filesystem;
using testing::expect_error_naming;
using testing::to_polydata;
using testing::write_text;
using MalformedMesh = testing::MalformedMeshTest;

std::string base64_decode(std::string_view text) {
  static const std::string A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    const auto v = A.find(c);
    if (v == std::string::npos) break;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    if ((bits += 6) >= 8) out.push_back(static_cast<char>((acc >> (bits -= 8)) & 0xff));
  }
  return out;
}

std::string base64_encode(std::string_view bytes) {
  static const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t v = 0;
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    for (std::size_t k = 0; k < 3; ++k)
      v = (v << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    for (std::size_t k = 0; k < 4; ++k) out.push_back(k <= n ? A[(v >> (18 - 6 * k)) & 63] : '=');
  }
  return out;
}

/// One triangle in VTK XML, appended raw and uncompressed with UInt32 headers: the points (the
/// size header says `points_bytes`), connectivity Int32 {0, 1, 2}, and the one cell offset `offset`
/// (Int32 or Int64).
template <class Offset>
std::string one_triangle_raw_vtp(Offset offset, std::uint32_t points_bytes = 36) {
  static_assert(std::is_same_v<Offset, std::int32_t> || std::is_same_v<Offset, std::int64_t>);
  std::string raw;
  auto put = [&](const auto& v) { raw.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(points_bytes);
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(v);
  put(std::uint32_t{12});
  for (std::int32_t v : {0, 1, 2}) put(v);
  put(static_cast<std::uint32_t>(sizeof(Offset)));
  put(offset);
  return cat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" ",
      "header_type=\"UInt32\">\n<PolyData>\n<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n",
      "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"0\"/></Points>\n",
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"40\"/>\n",
      "<DataArray type=\"", sizeof(Offset) == 8 ? "Int64" : "Int32",
      "\" Name=\"offsets\" format=\"appended\" offset=\"56\"/></Polys>\n",
      "</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_", raw, "\n</AppendedData>\n</VTKFile>\n");
}

TEST_F(MalformedMesh, VtpSizeHeadersBeyondTheFileAreRefusedBeforeVtkAllocates) {
  // write_vtp: appended base64 data, zlib, UInt64 headers [blocks, block size, last size, compressed
  // sizes], the header its own base64 stream; the Points array is at offset 0
  write_vtp(dir_ / "whole.vtp", kidney_phantom());
  const std::string vtp = testing::read_text(dir_ / "whole.vtp");
  const std::size_t data = vtp.find('_', vtp.find("<AppendedData")) + 1;
  const std::size_t header_chars = 44;  // 4 words = 32 bytes
  auto patched = [&](std::size_t word, std::uint64_t value) {
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    EXPECT_EQ(h.size(), 32u);
    for (int k = 0; k < 8; ++k) h[8 * word + k] = static_cast<char>((value >> (8 * k)) & 0xff);
    std::string b = vtp;
    b.replace(data, header_chars, base64_encode(h));
    return b;
  };
  write_text(dir_ / "same.vtp", patched(0, 1));  // the helpers re-encode the header faithfully
  EXPECT_EQ(testing::read_text(dir_ / "same.vtp"), vtp);
  write_text(dir_ / "blocks.vtp", patched(0, std::uint64_t(1) << 60));  // block count
  expect_error_naming(
      [&] { read_mesh(dir_ / "blocks.vtp"); },
      "blocks.vtp: VTK XML: DataArray 'Points' declares 1152921504606846976 compressed blocks");
  write_text(dir_ / "packed.vtp", patched(3, std::uint64_t(1) << 40));  // compressed size of block 0
  expect_error_naming([&] { read_mesh(dir_ / "packed.vtp"); }, "compressed bytes, the file holds");
  write_text(dir_ / "unpacked.vtp", patched(1, std::uint64_t(1) << 39));  // uncompressed block size
  expect_error_naming([&] { read_mesh(dir_ / "unpacked.vtp"); }, "uncompressed bytes from");
  {  // pieces whose point counts each fit in the file, but not together: VTK allocates for the sum
    std::string pieces =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<PolyData>\n";
    for (int k = 0; k < 3; ++k) pieces += "<Piece NumberOfPoints=\"900\" NumberOfPolys=\"0\"></Piece>\n";
    pieces += "</PolyData>\n</VTKFile>\n";
    write_text(dir_ / "pieces.vtp", pieces);
    expect_error_naming([&] { read_mesh(dir_ / "pieces.vtp"); },
                        "pieces.vtp: VTK XML: the pieces' NumberOfPoints add up to 1800: more than a");
  }
  {  // no blocks and block size 0: vtkXMLDataParser still divides by the block size (fuzz_mesh_vtp, SIGFPE)
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    std::fill(h.begin(), h.begin() + 16, '\0');
    std::string b = vtp;
    b.replace(data, header_chars, base64_encode(h));
    write_text(dir_ / "no-blocks.vtp", b);
    expect_error_naming([&] { read_mesh(dir_ / "no-blocks.vtp"); },
                        "no-blocks.vtp: VTK XML: DataArray 'Points': compression header with block size 0");
  }

  // appended raw, uncompressed, UInt32 headers: one triangle
  write_text(dir_ / "raw.vtp", one_triangle_raw_vtp(std::int32_t{3}));
  EXPECT_EQ(read_mesh(dir_ / "raw.vtp").num_faces(), 1);
  write_text(dir_ / "raw-big.vtp", one_triangle_raw_vtp(std::int32_t{3}, 0x7fffffff));
  expect_error_naming([&] { read_mesh(dir_ / "raw-big.vtp"); },
                      "raw-big.vtp: VTK XML: DataArray '' declares 2147483647 bytes, the file holds");
}

TEST_F(MalformedMesh, VtpCellOffsetsBeyondTheConnectivityAreRefusedBeforeVtkAllocates) {
  // vtkXMLUnstructuredDataReader sizes the connectivity array by the last cell offset before it reads
  // it (fuzz_mesh_vtp: an offset of 3e9 allocated 24 GB). check_vtk_xml decodes the offsets (raw,
  // base64; zlib, LZ4, LZMA) and compares the last one with what the connectivity array declares.
  const SurfaceMesh kidney = kidney_phantom();
  const std::string last_offset = std::to_string(3 * kidney.num_faces());
  struct Mode {
    const char* name;
    int compressor;  // vtkXMLWriter::CompressorType
    bool appended, base64;
  };
  for (const Mode& mode : {Mode{"zlib-appended-base64", vtkXMLWriter::ZLIB, true, true},
                           Mode{"lz4-appended-base64", vtkXMLWriter::LZ4, true, true},
                           Mode{"lzma-binary", vtkXMLWriter::LZMA, false, true},
                           Mode{"zlib-binary", vtkXMLWriter::ZLIB, false, true},
                           Mode{"none-binary", vtkXMLWriter::NONE, false, true}}) {
    SCOPED_TRACE(mode.name);
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetInputData(to_polydata(kidney));
    writer->SetCompressorType(mode.compressor);
    writer->SetHeaderTypeToUInt64();
    if (mode.appended)
      writer->SetDataModeToAppended();
    else
      writer->SetDataModeToBinary();
    writer->SetEncodeAppendedData(mode.base64);
    const fs::path good = dir_ / cat(mode.name, ".vtp");
    writer->SetFileName(good.string().c_str());
    ASSERT_EQ(writer->Write(), 1);
    EXPECT_EQ(read_mesh(good).num_faces(), kidney.num_faces());  // the check refuses no valid file

    // the connectivity array's header: 4 UInt64 words (1 block; uncompressed: 1 word), 44 base64 chars
    std::string vtp = testing::read_text(good);
    const std::size_t tag = vtp.find("Name=\"connectivity\"", vtp.find("<Polys"));
    ASSERT_NE(tag, std::string::npos);
    std::size_t data = 0;
    if (mode.appended) {
      const std::size_t off = vtp.find("offset=\"", tag) + 8;
      data = vtp.find('_', vtp.find("<AppendedData")) + 1 + std::stoul(vtp.substr(off));
    } else {
      data = vtp.find_first_not_of(" \t\r\n", vtp.find('>', tag) + 1);
    }
    const bool compressed = mode.compressor != vtkXMLWriter::NONE;
    const std::size_t header_chars = compressed ? 44 : 12;
    std::string h = base64_decode(std::string_view(vtp).substr(data, header_chars));
    // compressed: the header is a base64 stream of its own (32 bytes); uncompressed: one stream with
    // the data (12 characters = the 8-byte size and the first data byte)
    ASSERT_EQ(h.size(), compressed ? 32u : 9u);
    const std::uint64_t one_value = 8;  // the connectivity now declares one Int64 value
    for (int k = 0; k < 8; ++k)
      h[(compressed ? 16 : 0) + k] = static_cast<char>((one_value >> (8 * k)) & 0xff);
    vtp.replace(data, header_chars, base64_encode(h));
    const fs::path bad = dir_ / cat(mode.name, "-short.vtp");
    write_text(bad, vtp);
    expect_error_naming([&] { read_mesh(bad); },
                        cat(bad.filename().string(), ": VTK XML: piece 0: Polys offsets end at ", last_offset,
                            " connectivity values, the connectivity array holds 1"));
  }

  // ascii, and appended raw with a 2e9 offset (the fuzzer's case): one triangle
  const std::string ascii =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "<PolyData>\n<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">\n"
      "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 "
      "0</DataArray></Points>\n"
      "<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray>\n"
      "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">OFFSET</DataArray></Polys>\n"
      "</Piece>\n</PolyData>\n</VTKFile>\n";
  auto with_offset = [&](const std::string& v) {
    std::string s = ascii;
    s.replace(s.find("OFFSET"), 6, v);
    return s;
  };
  write_text(dir_ / "ascii.vtp", with_offset("3"));
  EXPECT_EQ(read_mesh(dir_ / "ascii.vtp").num_faces(), 1);
  write_text(dir_ / "ascii-huge.vtp", with_offset("2000000000"));
  expect_error_naming(
      [&] { read_mesh(dir_ / "ascii-huge.vtp"); },
      "ascii-huge.vtp: VTK XML: piece 0: Polys offsets end at 2000000000 connectivity values, "
      "the connectivity array holds 3");
  write_text(dir_ / "ascii-negative.vtp", with_offset("-5"));
  expect_error_naming([&] { read_mesh(dir_ / "ascii-negative.vtp"); },
                      "ascii-negative.vtp: VTK XML: piece 0: Polys offsets hold -5 (offsets are >= 0)");

  write_text(dir_ / "raw3.vtp", one_triangle_raw_vtp(std::int64_t{3}));
  EXPECT_EQ(read_mesh(dir_ / "raw3.vtp").num_faces(), 1);
  write_text(dir_ / "raw-huge.vtp", one_triangle_raw_vtp(std::int64_t{3'000'000'000}));
  // VTK reads an array with an `offset` attribute from the appended section whatever its `format` says
  // (fuzz_centerline: format="1ppended")
  std::string misspelled = one_triangle_raw_vtp(std::int64_t{3'000'000'000});
  misspelled.replace(misspelled.find("format=\"appended\" offset=\"56\""), 17, "format=\"1ppended\"");
  write_text(dir_ / "raw-misspelled.vtp", misspelled);
  expect_error_naming([&] { read_mesh(dir_ / "raw-misspelled.vtp"); },
                      "Polys offsets end at 3000000000 connectivity values");
  expect_error_naming([&] { read_mesh(dir_ / "raw-huge.vtp"); },
                      "raw-huge.vtp: VTK XML: piece 0: Polys offsets end at 3000000000 connectivity values, "
                      "the connectivity array holds 3");
}

TEST_F(MalformedMesh, VtpWithOutOfRangeIndexOrNanPointIsNamed) {
  SurfaceMesh m;
  m.V.resize(3, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.F.resize(1, 3);
  m.F << 0, 1, 2;
  auto poly = to_polydata(m);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  // index 7 of 3 points
  vtkNew<vtkCellArray> bad;
  const vtkIdType ids[3] = {0, 1, 7};
  bad->InsertNextCell(3, ids);
  poly->SetPolys(bad);
  writer->SetFileName((dir_ / "index.vtp").string().c_str());
  ASSERT_EQ(writer->Write(), 1);
  expect_error_naming([&] { read_mesh(dir_ / "index.vtp"); }, "index.vtp: polygon 0 references point 7");
  // NaN coordinate
  poly = to_polydata(m);
  poly->GetPoints()->SetPoint(1, std::numeric_limits<double>::quiet_NaN(), 0, 0);
  writer->SetInputData(poly);
  writer->SetFileName((dir_ / "nan.vtp").string().c_str());
  ASSERT_EQ(writer->Write(), 1);
  expect_error_naming([&] { read_mesh(dir_ / "nan.vtp"); }, "nan.vtp: point 1 has non-finite coordinates");
}

}  // namespace
}  // namespace medspring
