#include "support/vtk_xml.hpp"

#include "support/atomic_file.hpp"

#include <vtkErrorCode.h>
#include <vtkXMLWriter.h>

#include <stdexcept>
#include <string>

namespace drom {

void write_vtk_xml(vtkXMLWriter& writer, const std::filesystem::path& path) {
  AtomicFile file(path);
  writer.SetFileName(file.temporary_path().c_str());
  writer.SetDataModeToAppended();
  writer.SetCompressorTypeToZLib();
  const int written = writer.Write();
  const unsigned long error = writer.GetErrorCode();
  if (written != 1 || error != vtkErrorCode::NoError)
    throw std::runtime_error("cannot write " + path.string() +
                             (error == vtkErrorCode::OutOfDiskSpaceError ? ": No space left on device" : ": VTK error " + std::to_string(error)));
  file.commit();
}

}  // namespace drom
