#include "support/vtk_xml.hpp"

#include "support/atomic_file.hpp"

#include <vtkXMLWriter.h>

#include <stdexcept>

namespace drom {

void write_vtk_xml(vtkXMLWriter& writer, const std::filesystem::path& path) {
  AtomicFile file(path);
  writer.SetFileName(file.temporary_path().c_str());
  writer.SetDataModeToAppended();
  writer.SetCompressorTypeToZLib();
  if (writer.Write() != 1) throw std::runtime_error("cannot write " + path.string());
  file.commit();
}

}  // namespace drom
