#include "support/vtk_xml.hpp"

#include "support/atomic_file.hpp"

#include <vtkErrorCode.h>
#include <vtkObject.h>
#include <vtkXMLWriter.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace drom {

void write_vtk_xml(vtkXMLWriter& writer, const std::filesystem::path& path) {
  AtomicFile file(path);
  writer.SetFileName(file.temporary_path().c_str());
  writer.SetDataModeToAppended();
  writer.SetCompressorTypeToZLib();
  // VTK's own report of a failed write is a page of pipeline state on stderr: drom says it in one line.
  const int warnings = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  const int written = writer.Write();
  vtkObject::SetGlobalWarningDisplay(warnings);
  // The error code is errno below VTK's own codes (ENOSPC on a full disk).
  const unsigned long error = writer.GetErrorCode();
  if (written != 1 || error != vtkErrorCode::NoError) {
    const std::string why = error == vtkErrorCode::OutOfDiskSpaceError ? "No space left on device"
                            : error > 0 && error < vtkErrorCode::FirstVTKErrorCode ? std::strerror(static_cast<int>(error))
                                                                                  : "VTK error " + std::to_string(error);
    throw std::runtime_error("cannot write " + path.string() + ": " + why);
  }
  file.commit();
}

}  // namespace drom
