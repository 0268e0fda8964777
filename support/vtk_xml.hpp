#pragma once
// Writes a VTK XML file (.vtu, .vtp, ...) atomically: appended, zlib-compressed, written to a
// temporary file and renamed, so ParaView never opens a half-written file.
#include <filesystem>

class vtkXMLWriter;

namespace drom {

// `writer` already has its input set; throws std::runtime_error on failure.
void write_vtk_xml(vtkXMLWriter& writer, const std::filesystem::path& path);

}  // namespace drom
