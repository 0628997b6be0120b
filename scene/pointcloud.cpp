#include "scene/pointcloud.hpp"

#include <vtkErrorCode.h>
#include <vtkObject.h>

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "scene/files.hpp"
#include "scene/input.hpp"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLReader.h>
#include <vtkXMLPUnstructuredGridWriter.h>

namespace swmpm::scene {

const PointArray* PointCloud::find(const std::string& name) const {
  for (const auto& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

const PointArray& PointCloud::get(const std::string& name, const std::string& where) const {
  if (const auto* a = find(name)) return *a;
  throw std::runtime_error(where + ": missing point array \"" + name + "\"");
}

PointArray& PointCloud::add(const std::string& name, int components) {
  arrays.push_back({name, components, std::vector<double>(points.size() * components, 0.0)});
  return arrays.back();
}

VtuCompression vtu_compression(const std::string& name) {
  if (name == "zlib") return VtuCompression::zlib;
  if (name == "lz4") return VtuCompression::lz4;
  if (name == "none") return VtuCompression::none;
  throw std::invalid_argument("output.compression: \"" + name + "\" is not one of zlib, lz4, none");
}

namespace {

/// The cells of write_vtu (one vertex per point) or write_lattice_vtu (pixels or voxels).
struct Cells {
  int type = VTK_VERTEX;
  std::vector<vtkIdType> connectivity;  // `per_cell` point ids per cell
  int per_cell = 1;
};

/// The cloud as a VTK grid that borrows the cloud's memory (the writers only read it).
vtkSmartPointer<vtkUnstructuredGrid> as_grid(const std::string& path, const PointCloud& cloud, const Cells& c) {
  const auto n = static_cast<vtkIdType>(cloud.size());
  // The writer only reads: VTK arrays borrow the cloud's memory (SetArray with save = 1) instead of
  // copying it, which keeps a frame's peak memory to the cloud itself.
  auto borrow = [n](const double* data, int components) {
    auto arr = vtkSmartPointer<vtkDoubleArray>::New();
    arr->SetNumberOfComponents(components);
    arr->SetArray(const_cast<double*>(data), n * components, /*save=*/1);
    return arr;
  };
  static_assert(sizeof(std::array<double, 3>) == 3 * sizeof(double));
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetData(borrow(cloud.points.empty() ? nullptr : cloud.points[0].data(), 3));

  const auto cells_n = static_cast<vtkIdType>(c.type == VTK_VERTEX ? n : c.connectivity.size() / c.per_cell);
  auto offsets = vtkSmartPointer<vtkIdTypeArray>::New();
  auto connectivity = vtkSmartPointer<vtkIdTypeArray>::New();
  offsets->SetNumberOfValues(cells_n + 1);
  connectivity->SetNumberOfValues(cells_n * c.per_cell);
  for (vtkIdType i = 0; i <= cells_n; ++i) offsets->SetValue(i, i * c.per_cell);
  for (vtkIdType i = 0; i < cells_n * c.per_cell; ++i)
    connectivity->SetValue(i, c.type == VTK_VERTEX ? i : c.connectivity[static_cast<std::size_t>(i)]);
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);

  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(c.type, cells);
  for (const auto& a : cloud.arrays) {
    if (a.values.size() != static_cast<std::size_t>(n) * a.components)
      throw std::runtime_error(path + ": array \"" + a.name + "\" has the wrong size");
    auto arr = borrow(a.values.data(), a.components);
    arr->SetName(a.name.c_str());
    grid->GetPointData()->AddArray(arr);
  }
  return grid;
}

/// VTK's XML writer settings of every frame: appended raw binary, the scene's compression.
template <class Writer>
void configure(Writer* writer, VtuCompression compression) {
  // VTK reports a failed write on stderr once per block (megabytes of it on a full disk); the
  // error code is read instead and reported once, as a WriteError naming the file.
  static const bool quiet_vtk = [] {
    vtkObject::GlobalWarningDisplayOff();
    return true;
  }();
  (void)quiet_vtk;
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();  // raw binary
  switch (compression) {
    case VtuCompression::zlib:
      writer->SetCompressorTypeToZLib();
      writer->SetCompressionLevel(1);
      break;
    case VtuCompression::lz4:
      writer->SetCompressorTypeToLZ4();
      break;
    case VtuCompression::none:
      writer->SetCompressorTypeToNone();
      break;
  }
}

/// Runs the writer; a failure (VTK's error code, read instead of its stderr) as one WriteError.
template <class Writer>
void write_checked(Writer* writer, const std::string& path, const char* what) {
  const int ok = writer->Write();
  const unsigned long code = writer->GetErrorCode();
  if (ok != 1 || code != vtkErrorCode::NoError)
    throw files::WriteError(path, code == vtkErrorCode::OutOfDiskSpaceError
                                      ? std::string("No space left on device (or past the file size limit)")
                                      : std::string(what) + " failed (" + vtkErrorCode::GetStringFromErrorCode(code) + ")");
}

void write_unstructured(const std::string& path, const PointCloud& cloud, const Cells& c, VtuCompression compression) {
  auto grid = as_grid(path, cloud, c);
  auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
  writer->SetInputData(grid);
  configure(writer.Get(), compression);
  files::write_atomically(path, [&](const std::string& temporary) {
    writer->SetFileName(temporary.c_str());
    write_checked(writer.Get(), path, "the VTU writer");
    // The stream's last buffer reaches the file when it is closed, after the writer's checks: a
    // complete VTU ends with its closing tag.
    std::ifstream back(temporary, std::ios::binary | std::ios::ate);
    const std::streamoff size = back ? static_cast<std::streamoff>(back.tellg()) : 0;
    char tail[16] = {};
    if (size >= 16) {
      back.seekg(size - 16);
      back.read(tail, 16);
    }
    if (size < 16 || std::string(tail, 16).find("</VTKFile>") == std::string::npos)
      throw files::WriteError(path, "the file is incomplete (No space left on device?)");
  });
}

}  // namespace

void write_pvtu_piece(const std::string& path, const PointCloud& cloud, int piece, int pieces,
                      VtuCompression compression) {
  auto grid = as_grid(path, cloud, Cells{});
  auto writer = vtkSmartPointer<vtkXMLPUnstructuredGridWriter>::New();
  writer->SetInputData(grid);
  configure(writer.Get(), compression);
  writer->SetFileName(path.c_str());
  writer->SetNumberOfPieces(pieces);
  writer->SetStartPiece(piece);
  writer->SetEndPiece(piece);
  // Every rank takes part in the summary (VTK's global controller gathers which pieces exist);
  // rank 0 writes it.
  writer->SetWriteSummaryFile(1);
  write_checked(writer.Get(), path, "the parallel VTU writer");
}

std::string pvtu_piece_name(const std::string& pvtu_name, int piece) {
  // VTK's name for a piece: the summary's name without ".pvtu", "_<piece>.vtu".
  return pvtu_name.substr(0, pvtu_name.size() - 5) + "_" + std::to_string(piece) + ".vtu";
}

void write_vtu(const std::string& path, const PointCloud& cloud, VtuCompression compression) {
  // One vertex cell per particle, so ParaView shows points without a filter.
  write_unstructured(path, cloud, Cells{}, compression);
}

void write_lattice_vtu(const std::string& path, const PointCloud& cloud, const std::array<int, 3>& nodes,
                       VtuCompression compression) {
  if (static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2] != cloud.size())
    throw std::runtime_error(path + ": " + std::to_string(cloud.size()) + " points for a lattice of " +
                             std::to_string(nodes[0]) + " x " + std::to_string(nodes[1]) + " x " +
                             std::to_string(nodes[2]) + " nodes");
  const bool three_d = nodes[2] > 1;
  Cells c{three_d ? VTK_VOXEL : VTK_PIXEL, {}, three_d ? 8 : 4};
  auto at = [&](int i, int j, int k) -> vtkIdType { return i + nodes[0] * (j + static_cast<vtkIdType>(nodes[1]) * k); };
  for (int k = 0; k < std::max(nodes[2] - 1, 1); ++k)
    for (int j = 0; j + 1 < nodes[1]; ++j)
      for (int i = 0; i + 1 < nodes[0]; ++i)
        for (int dk = 0; dk < (three_d ? 2 : 1); ++dk)  // pixel and voxel order: x fastest, then y, then z
          for (int dj = 0; dj < 2; ++dj)
            for (int di = 0; di < 2; ++di) c.connectivity.push_back(at(i + di, j + dj, k + dk));
  write_unstructured(path, cloud, c, compression);
}

PointCloud read_vtu(const std::string& path) {
  // VTK would block on a FIFO and read a device without end: a regular file only. Frames of large
  // runs are big, so the bound is generous.
  check_input_file(path, "VTU file", std::uintmax_t{64} << 30);
  // A frame of a run on several ranks (mpirun) is a .pvtu over one piece per rank: read as one.
  const bool pieces = path.size() > 5 && path.compare(path.size() - 5, 5, ".pvtu") == 0;
  vtkSmartPointer<vtkXMLReader> reader;
  if (pieces) reader = vtkSmartPointer<vtkXMLPUnstructuredGridReader>::New();
  else reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = vtkUnstructuredGrid::SafeDownCast(reader->GetOutputDataObject(0));
  if (grid == nullptr || reader->GetErrorCode() != 0)
    throw std::runtime_error(path + (pieces ? ": not a readable PVTU file (or a piece is missing)" : ": not a readable VTU file"));
  PointCloud cloud;
  const vtkIdType n = grid->GetNumberOfPoints();
  cloud.points.resize(n);
  for (vtkIdType i = 0; i < n; ++i) grid->GetPoint(i, cloud.points[i].data());
  vtkPointData* pd = grid->GetPointData();
  for (int k = 0; k < pd->GetNumberOfArrays(); ++k) {
    vtkDataArray* arr = pd->GetArray(k);
    if (arr == nullptr || arr->GetName() == nullptr) continue;
    PointArray a{arr->GetName(), arr->GetNumberOfComponents(), {}};
    a.values.resize(static_cast<std::size_t>(n) * a.components);
    for (vtkIdType i = 0; i < n; ++i)
      for (int c = 0; c < a.components; ++c) a.values[i * a.components + c] = arr->GetComponent(i, c);
    cloud.arrays.push_back(std::move(a));
  }
  return cloud;
}

void write_pvd(const std::string& path, const std::vector<PvdEntry>& entries) {
  // The PVD collection format is ParaView's; VTK has no writer for it, it is six lines of XML.
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  out << std::setprecision(17);
  for (const auto& e : entries)
    out << "    <DataSet timestep=\"" << e.time << "\" group=\"" << e.group << "\" part=\"" << e.part
        << "\" file=\"" << e.file << "\"/>\n";
  out << "  </Collection>\n</VTKFile>\n";
  files::write_text_atomically(path, out.str());
}

std::vector<PvdEntry> read_pvd(const std::string& path) {
  const std::string text = read_input_file(path, "PVD file");
  static const std::regex dataset(R"(<DataSet\s+([^>]*)/>)");
  static const std::regex attr(R"((\w+)\s*=\s*"([^"]*)\")");
  std::vector<PvdEntry> entries;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), dataset); it != std::sregex_iterator(); ++it) {
    PvdEntry e{0.0, "", 0, ""};
    const std::string attrs = (*it)[1];
    for (auto at = std::sregex_iterator(attrs.begin(), attrs.end(), attr); at != std::sregex_iterator(); ++at) {
      const std::string key = (*at)[1], value = (*at)[2];
      if (key == "timestep") e.time = std::stod(value);
      else if (key == "group") e.group = value;
      else if (key == "part") e.part = std::stoi(value);
      else if (key == "file") e.file = value;
    }
    entries.push_back(e);
  }
  return entries;
}

}  // namespace swmpm::scene
