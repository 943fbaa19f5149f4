// vtkSluiceReader: a .sluice file as a time series of vtkPolyData for
// ParaView and pvpython. Each time step is a frame: float32 points, one
// vertex cell per particle, point arrays `lod` (the stable LOD value),
// `layer` (0 unclassified, 1 surface, 2 interior, 3 blob) and the selected
// attributes (float32, the file's units); field data TimeValue.
//
// LodLevel keeps that fraction of the particles, the same ones in every
// frame, reading only the LOD tiers that hold them; Layers picks every
// particle or the surface and blobs. Frames asked for in order stream
// through sluice's prefetch pipeline (runtime/particle_stream.h).
//
// Errors: a file or frame that cannot be read is reported through
// vtkErrorMacro with sluice's message (file, frame, chunk) and gives an
// empty output, never a crash.
#pragma once

#include <memory>

#include "SluiceReadersModule.h"
#include "vtkPolyDataAlgorithm.h"

class vtkDataArraySelection;

class SLUICEREADERS_EXPORT vtkSluiceReader : public vtkPolyDataAlgorithm {
 public:
  static vtkSluiceReader* New();
  vtkTypeMacro(vtkSluiceReader, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetFileName(const char* name);
  const char* GetFileName() const;
  // Whether `name` is a .sluice file (its magic bytes).
  static int CanReadFile(const char* name);

  // Fraction of the particles kept, (0, 1]; 1 keeps every particle.
  void SetLodLevel(double level);
  double GetLodLevel() const;
  // 0: every particle; 1: the surface and the blobs.
  void SetLayers(int layers);
  int GetLayers() const;

  // The attributes (point arrays) to load; all are selected at first.
  int GetNumberOfPointArrays();
  const char* GetPointArrayName(int index);
  int GetPointArrayStatus(const char* name);
  void SetPointArrayStatus(const char* name, int status);
  vtkDataArraySelection* GetPointDataArraySelection();

 protected:
  vtkSluiceReader();
  ~vtkSluiceReader() override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

 private:
  vtkSluiceReader(const vtkSluiceReader&) = delete;
  void operator=(const vtkSluiceReader&) = delete;

  struct Internals;
  std::unique_ptr<Internals> internals_;
};
