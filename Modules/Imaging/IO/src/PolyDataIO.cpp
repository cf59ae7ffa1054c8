#include "cementsph/imaging/PolyDataIO.h"

#include "cementsph/imaging/AtomicFile.h"

#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkXMLPPolyDataReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <locale>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cementsph::imaging {

void writePolyData(vtkPolyData* surface, const std::string& path) {
  if (!surface) throw std::runtime_error(path + ": nothing to write");
  writeAtomically(path, [&](const std::string& tmp) {
    auto writer = vtkSmartPointer<vtkXMLPolyDataWriter>::New();
    writer->SetFileName(tmp.c_str());
    writer->SetInputData(surface);
    writer->SetDataModeToAppended();
    // Raw appended bytes, not base64: base64 encoding and its many small stream writes were a third of a
    // snapshot's cost (perf, 5 ml phantom run), and the file is a third smaller. VTK and ParaView read both.
    writer->EncodeAppendedDataOff();
    // LZ4: 4-5x faster than zlib for a few per cent more bytes (a 5 ml run writes a hundred snapshots).
    writer->SetCompressorTypeToLZ4();
    // Blocks of 1 MiB, not VTK's 32 KiB: 4 % fewer bytes and fewer block headers and writes for a snapshot of a
    // few MB (a 47 842-point snapshot: 2.26 MB against 2.35 MB). VTK's reader takes any block size.
    writer->SetBlockSize(1 << 20);
    // VTK reports a full disk through the error code only (Write() still returns 1).
    if (writer->Write() != 1 || writer->GetErrorCode() != 0)
      throw std::runtime_error("VTK could not write the surface (disk full or over the file size limit?)");
  });
}

namespace {

// VTK XML's word type name of an array's values ("Float32", "Int64", ...), or null where the raw writer does not
// take it (VTK_CHAR's signedness depends on the platform, bit and string arrays are not words).
const char* xmlWordType(const vtkDataArray* a) {
  const int size = a->GetDataTypeSize();
  switch (a->GetDataType()) {
  case VTK_FLOAT: return "Float32";
  case VTK_DOUBLE: return "Float64";
  case VTK_SIGNED_CHAR: case VTK_SHORT: case VTK_INT: case VTK_LONG: case VTK_LONG_LONG: case VTK_ID_TYPE:
    return size == 1 ? "Int8" : size == 2 ? "Int16" : size == 4 ? "Int32" : size == 8 ? "Int64" : nullptr;
  case VTK_UNSIGNED_CHAR: case VTK_UNSIGNED_SHORT: case VTK_UNSIGNED_INT: case VTK_UNSIGNED_LONG:
  case VTK_UNSIGNED_LONG_LONG:
    return size == 1 ? "UInt8" : size == 2 ? "UInt16" : size == 4 ? "UInt32" : size == 8 ? "UInt64" : nullptr;
  default: return nullptr;
  }
}

std::string xmlEscaped(const char* text) {
  std::string out;
  for (const char* c = text ? text : ""; *c; ++c) {
    switch (*c) {
    case '&': out += "&amp;"; break;
    case '<': out += "&lt;"; break;
    case '>': out += "&gt;"; break;
    case '"': out += "&quot;"; break;
    default: out += *c;
    }
  }
  return out;
}

// The raw appended file: the XML header names each array's block by its offset; the blocks follow the
// "<AppendedData encoding="raw"> _" marker, each a UInt64 byte count and the values in memory order.
class RawPolyDataFile {
public:
  // Returns false where an array cannot be written raw (the caller falls back to VTK's writer).
  bool add(std::ostringstream& xml, const std::string& indent, vtkDataArray* a, const char* name,
           std::optional<vtkIdType> fieldTuples = std::nullopt) {
    const char* type = a ? xmlWordType(a) : nullptr;
    if (!type || !a->HasStandardMemoryLayout() || !name || a->HasAComponentName()) return false;
    const std::uint64_t bytes = std::uint64_t(a->GetNumberOfValues()) * std::uint64_t(a->GetDataTypeSize());
    xml << indent << "<DataArray type=\"" << type << "\" Name=\"" << xmlEscaped(name) << "\" NumberOfComponents=\""
        << a->GetNumberOfComponents() << "\"";
    if (fieldTuples) xml << " NumberOfTuples=\"" << *fieldTuples << "\"";
    xml << " format=\"appended\" offset=\"" << offset_ << "\"/>\n";
    blocks_.push_back({bytes, bytes ? a->GetVoidPointer(0) : nullptr});
    offset_ += sizeof(std::uint64_t) + bytes;
    return true;
  }
  // A cell array's offsets as VTK XML holds them: the n end offsets, without vtkCellArray's leading 0.
  bool addCells(std::ostringstream& xml, const std::string& indent, vtkCellArray* cells) {
    vtkDataArray* connectivity = cells->GetConnectivityArray();
    vtkDataArray* offsets = cells->GetOffsetsArray();
    const char* type = xmlWordType(offsets);
    if (!add(xml, indent, connectivity, "connectivity") || !type || !offsets->HasStandardMemoryLayout()) return false;
    const vtkIdType n = offsets->GetNumberOfValues() - 1;
    const std::uint64_t bytes = n > 0 ? std::uint64_t(n) * std::uint64_t(offsets->GetDataTypeSize()) : 0;
    xml << indent << "<DataArray type=\"" << type << "\" Name=\"offsets\" format=\"appended\" offset=\"" << offset_
        << "\"/>\n";
    blocks_.push_back({bytes, bytes ? static_cast<const char*>(offsets->GetVoidPointer(0)) + offsets->GetDataTypeSize()
                                    : nullptr});
    offset_ += sizeof(std::uint64_t) + bytes;
    return true;
  }
  void write(const std::string& header, const std::string& path) const {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
    if (!file) throw std::runtime_error(std::string("cannot create the file (") + std::strerror(errno) + ")");
    bool ok = std::fwrite(header.data(), 1, header.size(), file.get()) == header.size();
    for (const auto& [bytes, data] : blocks_) {
      ok = ok && std::fwrite(&bytes, sizeof bytes, 1, file.get()) == 1;
      if (bytes) ok = ok && std::fwrite(data, 1, bytes, file.get()) == bytes;
    }
    static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
    ok = ok && std::fwrite(tail, 1, sizeof tail - 1, file.get()) == sizeof tail - 1;
    ok = std::fflush(file.get()) == 0 && ok;
    if (std::fclose(file.release()) != 0) ok = false;
    if (!ok) throw std::runtime_error("could not write the points (disk full or over the file size limit?)");
  }

private:
  std::uint64_t offset_ = 0;
  std::vector<std::pair<std::uint64_t, const void*>> blocks_;
};

// The header and blocks of `data`, or false where some part needs VTK's writer.
bool describeRaw(vtkPolyData* data, std::ostringstream& xml, RawPolyDataFile& raw) {
  xml.imbue(std::locale::classic()); // no digit grouping in the counts and offsets, whatever the program's locale
  const std::uint16_t one = 1;
  const bool little = *reinterpret_cast<const std::uint8_t*>(&one) == 1;
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\""
      << (little ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n  <PolyData>\n";
  vtkFieldData* field = data->GetFieldData();
  if (field && field->GetNumberOfArrays() > 0) {
    xml << "    <FieldData>\n";
    for (int i = 0; i < field->GetNumberOfArrays(); ++i) {
      vtkDataArray* a = field->GetArray(i);
      if (!a || !raw.add(xml, "      ", a, a->GetName(), a->GetNumberOfTuples())) return false;
    }
    xml << "    </FieldData>\n";
  }
  vtkCellArray* cells[4] = {data->GetVerts(), data->GetLines(), data->GetStrips(), data->GetPolys()};
  const char* cellNames[4] = {"Verts", "Lines", "Strips", "Polys"};
  auto count = [](vtkCellArray* c) { return c ? c->GetNumberOfCells() : vtkIdType(0); };
  xml << "    <Piece NumberOfPoints=\"" << data->GetNumberOfPoints() << "\" NumberOfVerts=\"" << count(cells[0])
      << "\" NumberOfLines=\"" << count(cells[1]) << "\" NumberOfStrips=\"" << count(cells[2])
      << "\" NumberOfPolys=\"" << count(cells[3]) << "\">\n";
  auto attributes = [&](vtkDataSetAttributes* d, const char* tag) {
    if (!d || d->GetNumberOfArrays() == 0) return true;
    // What this writer does not carry goes to VTK's: the other attribute designations and unnamed arrays.
    for (int attribute : {vtkDataSetAttributes::TENSORS, vtkDataSetAttributes::TCOORDS, vtkDataSetAttributes::GLOBALIDS,
                          vtkDataSetAttributes::PEDIGREEIDS, vtkDataSetAttributes::TANGENTS})
      if (d->GetAbstractAttribute(attribute)) return false;
    xml << "      <" << tag;
    if (d->GetScalars() && d->GetScalars()->GetName()) xml << " Scalars=\"" << xmlEscaped(d->GetScalars()->GetName()) << "\"";
    if (d->GetVectors() && d->GetVectors()->GetName()) xml << " Vectors=\"" << xmlEscaped(d->GetVectors()->GetName()) << "\"";
    if (d->GetNormals() && d->GetNormals()->GetName()) xml << " Normals=\"" << xmlEscaped(d->GetNormals()->GetName()) << "\"";
    xml << ">\n";
    for (int i = 0; i < d->GetNumberOfArrays(); ++i) {
      vtkDataArray* a = d->GetArray(i);
      if (!a || !raw.add(xml, "        ", a, a->GetName())) return false;
    }
    xml << "      </" << tag << ">\n";
    return true;
  };
  if (!attributes(data->GetPointData(), "PointData") || !attributes(data->GetCellData(), "CellData")) return false;
  xml << "      <Points>\n";
  if (data->GetPoints() && !raw.add(xml, "        ", data->GetPoints()->GetData(), "Points")) return false;
  xml << "      </Points>\n";
  for (int k = 0; k < 4; ++k) {
    xml << "      <" << cellNames[k] << ">\n";
    if (count(cells[k]) > 0 && !raw.addCells(xml, "        ", cells[k])) return false;
    xml << "      </" << cellNames[k] << ">\n";
  }
  xml << "    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";
  return true;
}

} // namespace

void writePolyDataUncompressed(vtkPolyData* points, const std::string& path) {
  if (!points) throw std::runtime_error(path + ": nothing to write");
  std::ostringstream xml;
  RawPolyDataFile raw;
  if (!describeRaw(points, xml, raw)) return writePolyData(points, path);
  const std::string header = xml.str();
  writeAtomically(path, [&](const std::string& tmp) { raw.write(header, tmp); });
}

void writePolyDataPieces(const std::string& path, vtkPolyData* prototype, const std::vector<std::string>& pieceFiles) {
  if (!prototype) throw std::invalid_argument(path + ": no piece to describe");
  std::ostringstream xml;
  xml.imbue(std::locale::classic());
  auto declare = [&](vtkDataArray* a, const char* name, const char* indent) {
    const char* type = a ? xmlWordType(a) : nullptr;
    if (!type || !name) throw std::invalid_argument(path + ": a piece's array has no name or no word type");
    xml << indent << "<PDataArray type=\"" << type << "\" Name=\"" << xmlEscaped(name) << "\" NumberOfComponents=\""
        << a->GetNumberOfComponents() << "\"/>\n";
  };
  const std::uint16_t one = 1; // the pieces' byte order (they are this machine's: writePolyDataUncompressed)
  const bool little = *reinterpret_cast<const std::uint8_t*>(&one) == 1;
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PPolyData\" version=\"1.0\" byte_order=\""
      << (little ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n"
      << "  <PPolyData GhostLevel=\"0\">\n";
  for (const auto& [data, tag] : {std::pair<vtkDataSetAttributes*, const char*>{prototype->GetPointData(), "PPointData"},
                                  {prototype->GetCellData(), "PCellData"}}) {
    if (!data || data->GetNumberOfArrays() == 0) continue;
    xml << "    <" << tag << ">\n";
    for (int i = 0; i < data->GetNumberOfArrays(); ++i) declare(data->GetArray(i), data->GetArrayName(i), "      ");
    xml << "    </" << tag << ">\n";
  }
  if (prototype->GetPoints()) {
    xml << "    <PPoints>\n";
    declare(prototype->GetPoints()->GetData(), "Points", "      ");
    xml << "    </PPoints>\n";
  }
  for (const std::string& piece : pieceFiles) xml << "    <Piece Source=\"" << xmlEscaped(piece.c_str()) << "\"/>\n";
  xml << "  </PPolyData>\n</VTKFile>\n";
  writeTextAtomically(path, xml.str());
}

vtkSmartPointer<vtkPolyData> readPolyData(const std::string& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such file");
  // A .pvtp (writePolyDataPieces) is read whole: every piece it names, appended.
  vtkSmartPointer<vtkXMLReader> reader;
  if (std::filesystem::path(path).extension() == ".pvtp") reader = vtkSmartPointer<vtkXMLPPolyDataReader>::New();
  else reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
  // VTK's readers report some failures only as an error event (a .pvtp's piece that cannot be read leaves the
  // error code 0 and the output empty): caught here, so that it is this function's one error, not a line of
  // VTK's on stderr and fewer points.
  std::string error;
  auto onError = vtkSmartPointer<vtkCallbackCommand>::New();
  onError->SetClientData(&error);
  onError->SetCallback([](vtkObject*, unsigned long, void* clientData, void* callData) {
    auto& first = *static_cast<std::string*>(clientData);
    if (first.empty()) first = callData ? static_cast<const char*>(callData) : "error";
  });
  reader->AddObserver(vtkCommand::ErrorEvent, onError);
  reader->SetFileName(path.c_str());
  reader->Update();
  auto* output = vtkPolyData::SafeDownCast(reader->GetOutputDataObject(0));
  if (!error.empty()) {
    // VTK's text ends in a newline and may name the reader's address: the first line, the rest of it.
    std::string line = error.substr(0, error.find('\n'));
    const auto colon = line.find("): ");
    if (colon != std::string::npos) line = line.substr(colon + 3);
    throw std::runtime_error(path + ": cannot read (" + line + ")");
  }
  if (reader->GetErrorCode() != 0 || !output) throw std::runtime_error(path + ": cannot read surface");
  return output;
}

} // namespace cementsph::imaging
