#include "vtkSluiceReader.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "sluice/error.h"
#include "sluice/io/particles.h"
#include "sluice/io/reader.h"
#include "sluice/runtime/particle_stream.h"
#include "vtkCellArray.h"
#include "vtkCommand.h"
#include "vtkDataArraySelection.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTypeInt64Array.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnsignedShortArray.h"

vtkStandardNewMacro(vtkSluiceReader);

struct vtkSluiceReader::Internals {
  std::string file_name;
  double lod_level = 1;
  int layers = 0;
  vtkNew<vtkDataArraySelection> arrays;
  std::shared_ptr<const sluice::io::ContainerReader> reader;
  std::string opened;  // the file `reader` reads
  // The stream playing forward from the last frame asked for, and what it
  // was made for: a frame asked for next in order comes from it.
  std::unique_ptr<sluice::runtime::ParticleStream> stream;
  sluice::io::ParticleQuery streamed;
  std::vector<std::string> names;  // of streamed.attributes

  sluice::io::ParticleQuery query() const {
    sluice::io::ParticleQuery q;
    q.layers = layers == 1 ? sluice::io::LayerSet::surface() : sluice::io::LayerSet::particles();
    q.lod_level = float(lod_level);
    const auto& attributes = reader->header().attributes;
    for (size_t a = 0; a < attributes.size(); ++a) {
      if (arrays->ArrayIsEnabled(attributes[a].name.c_str())) q.attributes.push_back(a);
    }
    return q;
  }

  static bool same(const sluice::io::ParticleQuery& a, const sluice::io::ParticleQuery& b) {
    return a.layers == b.layers && a.lod_level == b.lod_level && a.attributes == b.attributes;
  }

  // Frame `frame`'s particles: from the stream when it is next there, else
  // from a new stream starting at it.
  sluice::io::ParticleArrays read(uint64_t frame) {
    const sluice::io::ParticleQuery q = query();
    if (!stream || !same(q, streamed) || stream->remaining() == 0 || stream->next_frame() != frame) {
      stream.reset();  // its pipeline stops before the next one starts
      stream = std::make_unique<sluice::runtime::ParticleStream>(
          reader, sluice::runtime::StreamRange{frame, reader->frame_count(), 1}, q, 0);
      streamed = q;
    }
    std::optional<sluice::runtime::StreamedFrame> f = stream->next();
    return std::move(f->arrays);
  }
};

vtkSluiceReader::vtkSluiceReader() : internals_(std::make_unique<Internals>()) {
  SetNumberOfInputPorts(0);
  internals_->arrays->AddObserver(vtkCommand::ModifiedEvent, this, &vtkSluiceReader::Modified);
}

vtkSluiceReader::~vtkSluiceReader() = default;

void vtkSluiceReader::PrintSelf(ostream& os, vtkIndent indent) {
  Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << internals_->file_name << "\n"
     << indent << "LodLevel: " << internals_->lod_level << "\n"
     << indent << "Layers: " << (internals_->layers == 1 ? "surface and blobs" : "every particle") << "\n";
}

void vtkSluiceReader::SetFileName(const char* name) {
  const std::string n = name ? name : "";
  if (n == internals_->file_name) return;
  internals_->file_name = n;
  Modified();
}
const char* vtkSluiceReader::GetFileName() const { return internals_->file_name.c_str(); }

int vtkSluiceReader::CanReadFile(const char* name) {
  std::ifstream in(name, std::ios::binary);
  char magic[8] = {};
  in.read(magic, sizeof magic);
  return in && std::memcmp(magic, "\x89SLUICE\n", 8) == 0 ? 1 : 0;  // io/format.h: the file's first 8 bytes
}

void vtkSluiceReader::SetLodLevel(double level) {
  level = std::clamp(level, 0.001, 1.0);
  if (level == internals_->lod_level) return;
  internals_->lod_level = level;
  Modified();
}
double vtkSluiceReader::GetLodLevel() const { return internals_->lod_level; }

void vtkSluiceReader::SetLayers(int layers) {
  layers = layers == 1 ? 1 : 0;
  if (layers == internals_->layers) return;
  internals_->layers = layers;
  Modified();
}
int vtkSluiceReader::GetLayers() const { return internals_->layers; }

int vtkSluiceReader::GetNumberOfPointArrays() { return internals_->arrays->GetNumberOfArrays(); }
const char* vtkSluiceReader::GetPointArrayName(int index) { return internals_->arrays->GetArrayName(index); }
int vtkSluiceReader::GetPointArrayStatus(const char* name) { return internals_->arrays->ArrayIsEnabled(name); }
void vtkSluiceReader::SetPointArrayStatus(const char* name, int status) {
  if (status) internals_->arrays->EnableArray(name);
  else internals_->arrays->DisableArray(name);
}
vtkDataArraySelection* vtkSluiceReader::GetPointDataArraySelection() { return internals_->arrays; }

int vtkSluiceReader::RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector* out) {
  Internals& in = *internals_;
  if (in.file_name.empty()) {
    vtkErrorMacro("no file name given");
    return 0;
  }
  try {
    if (!in.reader || in.opened != in.file_name) {
      in.stream.reset();
      in.reader = std::make_shared<sluice::io::ContainerReader>(in.file_name);
      in.opened = in.file_name;
      for (const auto& a : in.reader->header().attributes) {
        if (!in.arrays->ArrayExists(a.name.c_str())) in.arrays->AddArray(a.name.c_str());
      }
    }
  } catch (const sluice::Error& e) {
    in.reader.reset();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  std::vector<double> times;
  for (const auto& e : in.reader->index().frames) times.push_back(e.time);
  vtkInformation* info = out->GetInformationObject(0);
  info->Remove(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  info->Remove(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
  if (!times.empty()) {
    info->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(), int(times.size()));
    const double range[2] = {times.front(), times.back()};
    info->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  }
  return 1;
}

namespace {

// The frame whose time is the latest at or before `t` (the first frame
// for a time before it): ParaView's rule for a time between steps.
uint64_t frame_at(const sluice::io::ContainerReader& reader, double t) {
  const auto& frames = reader.index().frames;
  uint64_t f = 0;
  while (f + 1 < frames.size() && frames[f + 1].time <= t) ++f;
  return f;
}

template <class Array, class T>
vtkNew<Array> array_of(const char* name, const std::vector<T>& values, int components = 1) {
  vtkNew<Array> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(vtkIdType(values.size() / size_t(components)));
  std::copy(values.begin(), values.end(), a->GetPointer(0));
  return a;
}

}  // namespace

int vtkSluiceReader::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* out) {
  Internals& in = *internals_;
  if (!in.reader) return 0;
  vtkInformation* info = out->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::SafeDownCast(info->Get(vtkDataObject::DATA_OBJECT()));
  const double t = info->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
                       ? info->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
                       : in.reader->index().frames.empty() ? 0.0 : in.reader->index().frames.front().time;
  if (in.reader->frame_count() == 0) return 1;
  const uint64_t frame = frame_at(*in.reader, t);
  sluice::io::ParticleArrays p;
  try {
    p = in.read(frame);
  } catch (const sluice::Error& e) {
    in.stream.reset();
    vtkErrorMacro(<< e.what());
    return 0;
  }
  const auto n = vtkIdType(p.count());
  vtkNew<vtkPoints> points;
  points->SetData(array_of<vtkFloatArray>("Points", p.positions, 3));
  output->SetPoints(points);
  vtkNew<vtkTypeInt64Array> offsets, connectivity;
  offsets->SetNumberOfTuples(n + 1);
  connectivity->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i) {
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(n, n);
  vtkNew<vtkCellArray> vertices;
  vertices->SetData(offsets, connectivity);
  output->SetVerts(vertices);
  vtkPointData* pd = output->GetPointData();
  pd->AddArray(array_of<vtkUnsignedShortArray>("lod", p.lod));
  pd->AddArray(array_of<vtkUnsignedCharArray>("layer", p.layer));
  const sluice::io::ParticleQuery q = in.streamed;
  for (size_t k = 0; k < q.attributes.size(); ++k) {
    const std::string& name = in.reader->header().attributes[q.attributes[k]].name;
    pd->AddArray(array_of<vtkFloatArray>(name.c_str(), p.attributes[k]));
    if (k == 0) pd->SetActiveScalars(name.c_str());
  }
  vtkNew<vtkDoubleArray> time;
  time->SetName("TimeValue");
  time->InsertNextValue(p.time);
  output->GetFieldData()->AddArray(time);
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), in.reader->index().frames[frame].time);
  return 1;
}
