// vtk_fluid_peer: the VTK peer of `sluice bench render --vtk`, native, for a
// VTK built with EGL (bench/vtk_peer/build.sh) so that vtkOpenGLFluidMapper
// runs headless on a GPU driver, with no X server and no Python.
//
//   vtk_fluid_peer XYZ WIDTH HEIGHT RADIUS REPEATS IMAGE CAMERA
//
// XYZ: float32 x,y,z triples. CAMERA: "ex,ey,ez,tx,ty,tz,ux,uy,uz,fov_deg".
// IMAGE: "" or a path that gets the last frame as raw RGBA8 rows, top first
// (the bench writes the PNG). Prints "VTKPEER <median seconds per frame>
// <VTK version> <GL renderer>" on success. The settings match the Python
// peer in render_bench.cpp: narrow-range filter, transparent fluid volume,
// no multisampling, the renderer's last culler removed.
#include <vtkCamera.h>
#include <vtkCullerCollection.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkOpenGLFluidMapper.h>
#include <vtkOpenGLRenderWindow.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkVersion.h>
#include <vtkVolume.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

std::vector<float> read_points(const char* path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error(std::string("cannot open ") + path);
  const std::streamsize bytes = in.tellg();
  if (bytes <= 0 || bytes % 12 != 0) throw std::runtime_error(std::string(path) + ": not float32 x,y,z triples");
  std::vector<float> xyz(size_t(bytes) / 4);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(xyz.data()), bytes);
  if (!in) throw std::runtime_error(std::string("cannot read ") + path);
  return xyz;
}

std::vector<double> parse_camera(const std::string& text) {
  std::vector<double> v;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) v.push_back(std::stod(item));
  if (v.size() != 10) throw std::runtime_error("camera: expected 10 comma-separated numbers");
  return v;
}

int run(int argc, char** argv) {
  if (argc != 8) {
    std::fprintf(stderr, "usage: %s XYZ WIDTH HEIGHT RADIUS REPEATS IMAGE CAMERA\n", argv[0]);
    return 2;
  }
  std::vector<float> xyz = read_points(argv[1]);
  const int width = std::atoi(argv[2]), height = std::atoi(argv[3]), repeats = std::max(1, std::atoi(argv[5]));
  const double radius = std::atof(argv[4]);
  const std::string image = argv[6];
  const std::vector<double> cam = parse_camera(argv[7]);

  vtkNew<vtkFloatArray> array;
  array->SetNumberOfComponents(3);
  array->SetArray(xyz.data(), vtkIdType(xyz.size()), 1);  // 1: VTK does not free it
  vtkNew<vtkPoints> points;
  points->SetData(array);
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);

  vtkNew<vtkOpenGLFluidMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetParticleRadius(float(radius));
  mapper->SetSurfaceFilterMethod(vtkOpenGLFluidMapper::NarrowRange);
  mapper->SetDisplayMode(vtkOpenGLFluidMapper::TransparentFluidVolume);
  mapper->SetAttenuationColor(0.6f, 0.15f, 0.06f);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0.78, 0.85, 0.92);
  renderer->AddVolume(volume);
  vtkCullerCollection* cullers = renderer->GetCullers();
  cullers->RemoveItem(cullers->GetLastItem());
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->SetSize(width, height);
  window->AddRenderer(renderer);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(cam[0], cam[1], cam[2]);
  camera->SetFocalPoint(cam[3], cam[4], cam[5]);
  camera->SetViewUp(cam[6], cam[7], cam[8]);
  camera->SetViewAngle(cam[9]);
  renderer->ResetCameraClippingRange();

  auto* gl = vtkOpenGLRenderWindow::SafeDownCast(window);
  // Timed to completion: Render() only queues GL work on a GPU driver.
  auto frame = [&] {
    window->Render();
    if (gl) gl->WaitForCompletion();
  };
  frame();  // first use: buffers, shaders
  for (int i = 0; i < 3; ++i) frame();  // warm-up
  std::vector<double> seconds;
  for (int i = 0; i < repeats; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    frame();
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  std::string renderer_name = gl ? gl->ReportCapabilities() : std::string();
  const size_t at = renderer_name.find("OpenGL renderer string:");
  renderer_name = at == std::string::npos ? "unknown" : renderer_name.substr(at + 24, renderer_name.find('\n', at) - at - 24);
  std::printf("VTKPEER %.6f %s %s\n", seconds[seconds.size() / 2], vtkVersion::GetVTKVersion(), renderer_name.c_str());

  if (!image.empty()) {
    vtkNew<vtkUnsignedCharArray> pixels;
    window->GetRGBACharPixelData(0, 0, width - 1, height - 1, /*front=*/0, pixels);
    std::ofstream out(image, std::ios::binary);
    for (int y = height - 1; y >= 0; --y) {  // GL rows are bottom first
      out.write(reinterpret_cast<const char*>(pixels->GetPointer(vtkIdType(y) * width * 4)), std::streamsize(width) * 4);
    }
    if (!out) throw std::runtime_error("cannot write " + image);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vtk_fluid_peer: %s\n", e.what());
    return 1;
  }
}
