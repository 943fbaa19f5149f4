// VTK used as the peer in comparisons: its writer (sizes) and its readers as
// a user runs them (speed).
#include "sluice/io/error.h"
#include "sluice/io/import.h"

#ifdef SLUICE_WITH_VTK
#include <vtkCellType.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>
#include <vtkDataSet.h>
#include <vtkSmartPointer.h>
#include <vtkGenericDataObjectReader.h>
#include <vtkXMLGenericDataObjectReader.h>
#endif

namespace sluice::io {

#ifdef SLUICE_WITH_VTK

bool has_vtk_support() { return true; }

void write_vtu(const std::string& path, const ParticleFrame& frame, bool compress) {
  const auto n = static_cast<vtkIdType>(frame.count());
  vtkNew<vtkFloatArray> coords;
  coords->SetNumberOfComponents(3);
  coords->SetNumberOfTuples(n);
  std::copy(frame.positions.begin(), frame.positions.end(), coords->GetPointer(0));
  vtkNew<vtkPoints> points;
  points->SetData(coords);
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->Allocate(n);
  for (vtkIdType i = 0; i < n; ++i) grid->InsertNextCell(VTK_VERTEX, 1, &i);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  if (compress) writer->SetCompressorTypeToZLib();
  else writer->SetCompressorTypeToNone();
  if (writer->Write() != 1) throw Error({path}, "VTK could not write the file");
}

uint64_t read_with_vtk(const std::string& path) {
  const bool legacy = path.size() > 4 && path.compare(path.size() - 4, 4, ".vtk") == 0;
  vtkSmartPointer<vtkDataObject> output;
  if (legacy) {
    vtkNew<vtkGenericDataObjectReader> reader;
    reader->SetFileName(path.c_str());
    reader->ReadAllScalarsOn();
    reader->ReadAllVectorsOn();
    reader->ReadAllFieldsOn();
    reader->Update();
    output = reader->GetOutput();
  } else {
    vtkNew<vtkXMLGenericDataObjectReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    output = reader->GetOutput();
  }
  auto* data = vtkDataSet::SafeDownCast(output);
  if (data == nullptr) throw Error({path}, "VTK read no dataset");
  return static_cast<uint64_t>(data->GetNumberOfPoints());
}

#else

bool has_vtk_support() { return false; }

uint64_t read_with_vtk(const std::string& path) {
  throw Error({path}, "this sluice was built without VTK: install libvtk9-dev and rebuild");
}

void write_vtu(const std::string& path, const ParticleFrame&, bool) {
  throw Error({path}, "this sluice was built without VTK: install libvtk9-dev and rebuild to write .vtu files");
}

#endif

}  // namespace sluice::io
