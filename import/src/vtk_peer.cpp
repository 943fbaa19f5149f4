// VTK used as the peer in comparisons: its writer (sizes) and its readers as
// a user runs them (speed).
#include "sluice/error.h"
#include "sluice/import/source.h"
#include "sluice/import/vtk.h"

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
#include <vtkCellArray.h>
#include <vtkDataArraySelection.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataWriter.h>
#include <vtkUnsignedIntArray.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <type_traits>
#endif

namespace sluice::import {

using namespace sluice::io;  // the container's types: frames, errors, shapes
using io::Error;  // (not sluice::Error, its base)

#ifdef SLUICE_WITH_VTK

bool has_vtk_support() { return true; }

namespace {

// The frame as a VTK dataset of type T (unstructured grid or polydata), one
// vertex per particle, with its id and attribute arrays.
template <class T>
vtkSmartPointer<T> peer_dataset(const ParticleFrame& frame, const PeerArrays& arrays) {
  const auto n = static_cast<vtkIdType>(frame.count());
  vtkNew<vtkFloatArray> coords;
  coords->SetNumberOfComponents(3);
  coords->SetNumberOfTuples(n);
  std::copy(frame.positions.begin(), frame.positions.end(), coords->GetPointer(0));
  vtkNew<vtkPoints> points;
  points->SetData(coords);
  auto data = vtkSmartPointer<T>::New();
  data->SetPoints(points);
  vtkNew<vtkCellArray> cells;
  for (vtkIdType i = 0; i < n; ++i) cells->InsertNextCell(1, &i);
  if constexpr (std::is_same_v<T, vtkPolyData>) {
    data->SetVerts(cells);
  } else {
    data->SetCells(VTK_VERTEX, cells);
  }
  if (!arrays.id_name.empty() && frame.ids.size() == frame.count()) {
    vtkNew<vtkUnsignedIntArray> ids;
    ids->SetName(arrays.id_name.c_str());
    ids->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) ids->SetValue(i, static_cast<unsigned>(frame.ids[static_cast<size_t>(i)]));
    data->GetPointData()->AddArray(ids);
  }
  for (size_t k = 0; k < frame.attributes.size() && k < arrays.attribute_names.size(); ++k) {
    vtkNew<vtkFloatArray> a;
    a->SetName(arrays.attribute_names[k].c_str());
    a->SetNumberOfTuples(n);
    std::copy(frame.attributes[k].begin(), frame.attributes[k].end(), a->GetPointer(0));
    data->GetPointData()->AddArray(a);
  }
  return data;
}

}  // namespace

void write_vtu(const std::string& path, const ParticleFrame& frame, bool compress, const PeerArrays& arrays) {
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(peer_dataset<vtkUnstructuredGrid>(frame, arrays));
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  if (compress) writer->SetCompressorTypeToZLib();
  else writer->SetCompressorTypeToNone();
  if (writer->Write() != 1) throw Error({path}, "VTK could not write the file");
}

void write_legacy_vtk(const std::string& path, const ParticleFrame& frame, const PeerArrays& arrays) {
  vtkNew<vtkPolyDataWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(peer_dataset<vtkPolyData>(frame, arrays));
  writer->SetFileTypeToBinary();
  writer->SetFileVersion(42);
  if (writer->Write() != 1) throw Error({path}, "VTK could not write the file");
}

uint64_t read_with_vtk(const std::string& path, const std::vector<std::string>* only) {
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
  } else if (only) {
    // The reader for the dataset type: its array selection is the file's.
    const bool poly = path.size() > 4 && path.compare(path.size() - 4, 4, ".vtp") == 0;
    vtkSmartPointer<vtkXMLReader> reader;
    if (poly) reader = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    else reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
    reader->SetFileName(path.c_str());
    reader->UpdateInformation();
    reader->GetPointDataArraySelection()->DisableAllArrays();
    for (const auto& name : *only) reader->GetPointDataArraySelection()->EnableArray(name.c_str());
    reader->GetCellDataArraySelection()->DisableAllArrays();
    reader->Update();
    output = reader->GetOutputDataObject(0);
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

uint64_t read_with_vtk(const std::string& path, const std::vector<std::string>*) {
  throw Error({path}, "this sluice was built without VTK: install libvtk9-dev and rebuild");
}

void write_vtu(const std::string& path, const ParticleFrame&, bool, const PeerArrays&) {
  throw Error({path}, "this sluice was built without VTK: install libvtk9-dev and rebuild to write .vtu files");
}

void write_legacy_vtk(const std::string& path, const ParticleFrame&, const PeerArrays&) {
  throw Error({path}, "this sluice was built without VTK: install libvtk9-dev and rebuild to write .vtk files");
}

#endif

}  // namespace sluice::import
