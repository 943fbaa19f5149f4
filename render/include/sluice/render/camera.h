// sluice/render/camera.h: a perspective camera with the interactions a
// viewer needs (orbit, pan, zoom, fit to bounds) and a text form to save and
// restore views: "eye=x,y,z;target=x,y,z;up=x,y,z;fov=deg[;near=n]".
//
// Units: world units for positions and distances, degrees for fov_deg.
// Plain value type; not thread-safe to mutate from several threads.
#pragma once

#include <string>

#include "sluice/render/math.h"

namespace sluice::render {

// A part of an image in fractions of its size: x right, y down, 0..1.
struct ScreenRect {
  float x0 = 0, y0 = 0, x1 = 1, y1 = 1;
};

struct Bounds {
  Vec3 min, max;
  Vec3 center() const { return (min + max) * 0.5f; }
  float diagonal() const { return length(max - min); }
};

class Camera {
 public:
  Vec3 eye{0, -3, 1};
  Vec3 target{0, 0, 0};
  Vec3 up{0, 0, 1};
  float fov_deg = 40.0f;  // vertical field of view
  float near = 0.0f;      // near plane distance; 0: automatic (distance to target / 1000)
  // Where the view's centre lies on the image, in normalized device
  // coordinates (x right, y down, -1..1; 0,0: the image centre): a lens
  // shift, so a view can be framed beside a panel that covers the rest.
  float shift_x = 0.0f, shift_y = 0.0f;

  // Rotates the eye about the target: yaw about `up`, pitch about the
  // camera's right axis (radians). Pitch stops short of the poles.
  void orbit(float yaw, float pitch);
  // Moves eye and target together by fractions of the view height at the
  // target's distance (dx right, dy up).
  void pan(float dx, float dy);
  // Moves the eye toward the target by factor (< 1 closer, > 1 farther).
  void zoom(float factor);
  // Keeps the viewing direction, moves the target to the box's centre and the
  // eye back until the box's bounding sphere fits the narrower fov.
  void fit(const Bounds& box, float aspect);
  // A default three-quarter view of `box` from a little above, `up` pointing
  // up on screen (any direction; a file's is SceneInfo::up), as near as
  // keeps every corner of the box in view.
  // `free`: the part of the image to frame the data in (the rest may be
  // covered, by a HUD for one); the lens shift centres the view there.
  static Camera framing(const Bounds& box, Vec3 up, float aspect, float fov_deg = 40.0f, ScreenRect free = {});

  float near_plane() const;
  Vec3 forward() const { return normalize(target - eye); }
  Mat4 view() const { return look_at(eye, target, up); }
  Mat4 projection(float aspect) const;

  // "eye=..;target=..;up=..;fov=.." with 9 significant digits (and
  // ";near=..", ";shift=x,y" when they are not 0).
  std::string to_string() const;
  // Parses the form above; keys may come in any order and be omitted (they
  // keep this camera's values). Throws render::Error naming the bad key.
  void apply(const std::string& text);

  bool operator==(const Camera&) const = default;

 private:
  // The nearest eye, along the current view direction, that sees every
  // corner of `box` (with a 10% margin).
  void fit_corners(const Bounds& box, float tan_half_v, float aspect);
};

// A rectangle of the target in pixels (origin top left).
struct Viewport {
  uint32_t x = 0, y = 0;
  uint32_t width = 0, height = 0;
};

// One eye or camera. Matrices are column-major (math.h).
//  - view: world -> eye space (right-handed, looking down -z, +y up).
//  - projection: eye -> Vulkan clip space (x right, y down, depth 0..1) as
//    the host's own rasterizer uses it; asymmetric frusta (OpenXR's per-eye
//    fov) and reversed or standard depth, finite or infinite far plane, are
//    all accepted. The fluid's depth is written with this projection, and the
//    depth test follows its direction (greater-or-equal for reversed depth).
struct View {
  Mat4 view = Mat4::identity();
  Mat4 projection = Mat4::identity();
  Viewport viewport;
};
// The view of `camera` over `viewport` (aspect from the viewport).
View camera_view(const Camera& camera, const Viewport& viewport);

}  // namespace sluice::render
