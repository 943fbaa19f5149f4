// sluice/xr/pose.h: rigid poses (a rotation and a position) as OpenXR gives
// them, and the little arithmetic the controls and the eye views need. Plain
// values; no OpenXR or Vulkan here, so it is cheap to test.
//
// Conventions are OpenXR's: right-handed, +y up, a pose maps points of its
// own frame into its parent's (p_parent = rotate(orientation, p) + position).
#pragma once

#include "sluice/render/math.h"

namespace sluice::xr {

using render::Mat4;
using render::Vec3;

// A unit quaternion (x, y, z vector part, w scalar part), as XrQuaternionf.
struct Quat {
  float x = 0, y = 0, z = 0, w = 1;
};

Quat operator*(Quat a, Quat b);  // a after b
Quat conjugate(Quat q);
Quat normalize(Quat q);          // the identity for a zero quaternion
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

}  // namespace sluice::xr
