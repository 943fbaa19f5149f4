// sluice/xr/placement.h: poses as OpenXR gives them, where the data stands in
// the room, and each eye's view of it as the renderer takes it
// (render::View). Plain functions.
//
// Units: the room (an OpenXR reference space) is in metres, +y up; the data
// keeps its own units. A Placement maps data to room:
//   p_room = transform(pose, scale * p_data)
// Eye views are expressed in data units (the view matrix is rigid, so the
// renderer's radii, LOD distances and filters stay in the data's units), and
// the projection's planes are scaled to match: the depth written is the
// same value a room-metre projection with `near`/`far` gives, which is what
// the compositor's depth layer is told.
#pragma once

#include "sluice/render/frame.h"
#include "sluice/render/math.h"
#include "sluice/render/renderer.h"

namespace sluice::xr {

// Poses: rigid poses (a rotation and a position) as OpenXR gives
// them, and the little arithmetic the controls and the eye views need. Plain
// values; no OpenXR or Vulkan here, so it is cheap to test.
//
// Conventions are OpenXR's: right-handed, +y up, a pose maps points of its
// own frame into its parent's (p_parent = rotate(orientation, p) + position).

using render::Mat4;
using render::Vec3;

// A unit quaternion (x, y, z vector part, w scalar part), as XrQuaternionf.
struct Quat {
  float x = 0, y = 0, z = 0, w = 1;
};

Quat operator*(Quat a, Quat b);  // a after b
Quat conjugate(Quat q);
Quat normalize(Quat q);  // the identity for a zero quaternion
Vec3 rotate(Quat q, Vec3 v);
// Rotation by `radians` about `axis` (normalized here; identity for a zero axis).
Quat axis_angle(Vec3 axis, float radians);
// The shortest rotation taking direction `from` to direction `to`.
Quat rotation_between(Vec3 from, Vec3 to);

struct Pose {
  Quat orientation;
  Vec3 position;
};

Pose operator*(const Pose& a, const Pose& b);  // a after b: (a*b)(p) = a(b(p))
Pose inverse(const Pose& p);
Vec3 transform(const Pose& pose, Vec3 point);
Mat4 to_matrix(const Pose& pose);

struct Placement {
  Pose pose;
  float scale = 1;  // room metres per data unit
};

Vec3 to_room(const Placement& placement, Vec3 data_point);

// Which reference space the room is: STAGE has its origin on the floor;
// LOCAL at the head's starting position (the floor assumed eye_height below).
enum class Floor { Stage, Local };

struct PlacementOptions {
  float size = 1.5f;          // metres the data's largest extent spans
  float distance = 1.2f;      // metres in front of the origin (towards -z) to the data's centre
  float eye_height = 1.6f;    // LOCAL only: where the floor is assumed below the origin
};

// The data upright (the scene's up axis along the room's +y), its largest
// extent `size` metres, its lowest point on the floor, centred `distance`
// in front of the origin. Degenerate bounds give scale 1.
Placement initial_placement(const render::SceneInfo& scene, Floor floor, const PlacementOptions& options = {});

// An eye's field of view, radians (XrFovf: left and down negative).
struct Fov {
  float left = -0.7f, right = 0.7f, up = 0.7f, down = -0.7f;
};

// Eye -> Vulkan clip space (x right, y down) for an asymmetric field of view,
// with reversed depth: 1 at `near`, 0 at `far`, both positive distances in
// the units the eye space is in; far = infinity gives an infinite far plane.
Mat4 fov_projection(const Fov& fov, float near, float far);

// The renderer's view of one eye: `eye` is the eye's pose in the room,
// `near_m`/`far_m` the depth planes in metres.
render::View eye_view(const Pose& eye, const Fov& fov, const Placement& placement, float near_m, float far_m,
                      const render::Viewport& viewport);

}  // namespace sluice::xr
