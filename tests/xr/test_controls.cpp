// The XR module's plain code: poses, the eyes' projections, where the data
// stands, and what the controllers' actions do. No runtime needed.
#include <gtest/gtest.h>

#include <cmath>

#include "sluice/xr/controls.h"
#include "sluice/xr/placement.h"

namespace sluice::xr {
namespace {

constexpr float kPi = 3.14159265f;

void expect_near(Vec3 a, Vec3 b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

render::Vec4 project(const Mat4& m, Vec3 p) { return m * render::Vec4{p.x, p.y, p.z, 1}; }

TEST(Pose, InverseAndComposition) {
  const Pose a{axis_angle({1, 2, 3}, 0.7f), {0.3f, -1.0f, 2.0f}};
  const Pose b{axis_angle({0, 1, 0}, -1.2f), {1, 1, 1}};
  const Vec3 p{0.5f, -0.25f, 4};
  expect_near(transform(inverse(a) * a, p), p);
  expect_near(transform(a * b, p), transform(a, transform(b, p)));
  // The matrix does what the pose does.
  const render::Vec4 m = project(to_matrix(a), p);
  expect_near({m.x, m.y, m.z}, transform(a, p));
  // A quarter turn about +y takes +x to -z (right-handed).
  expect_near(rotate(axis_angle({0, 1, 0}, kPi / 2), {1, 0, 0}), {0, 0, -1});
  expect_near(rotate(rotation_between({0, 0, 1}, {0, 1, 0}), {0, 0, 1}), {0, 1, 0});
  expect_near(rotate(rotation_between({0, 1, 0}, {0, -1, 0}), {0, 1, 0}), {0, -1, 0});
}

TEST(Placement, FovProjectionPutsTheFieldEdgesOnTheImageEdges) {
  const Fov fov{-0.9f, 0.6f, 0.8f, -0.5f};  // asymmetric, as a headset's
  const float near = 0.05f, far = 100.0f;
  const Mat4 m = fov_projection(fov, near, far);
  const float z = -3;
  const auto ndc = [&](Vec3 p) {
    const render::Vec4 c = project(m, p);
    return Vec3{c.x / c.w, c.y / c.w, c.z / c.w};
  };
  EXPECT_NEAR(ndc({std::tan(fov.left) * -z, 0, z}).x, -1, 1e-5);
  EXPECT_NEAR(ndc({std::tan(fov.right) * -z, 0, z}).x, 1, 1e-5);
  EXPECT_NEAR(ndc({0, std::tan(fov.up) * -z, z}).y, -1, 1e-5);   // Vulkan: up is row 0
  EXPECT_NEAR(ndc({0, std::tan(fov.down) * -z, z}).y, 1, 1e-5);
  // Reversed depth: 1 at the near plane, 0 at the far one, n/d in between for an infinite far.
  EXPECT_NEAR(ndc({0, 0, -near}).z, 1, 1e-5);
  EXPECT_NEAR(ndc({0, 0, -far}).z, 0, 1e-5);
  const Mat4 inf = fov_projection(fov, near, INFINITY);
  const render::Vec4 c = project(inf, {0, 0, -2});
  EXPECT_NEAR(c.z / c.w, near / 2, 1e-7);
  // The renderer reads reversed depth from the sign of this entry.
  EXPECT_GT(m.at(2, 3), 0);
}

TEST(Placement, TheDataStandsOnTheFloorInFrontOfTheUser) {
  render::SceneInfo scene;  // z up, 4 x 2 x 1 data units
  scene.bounds = {{-1, 0, 0.5f}, {3, 2, 1.5f}};
  scene.up = {0, 0, 1};
  const Placement p = initial_placement(scene, Floor::Stage);
  EXPECT_NEAR(p.scale, 1.5f / 4, 1e-6);
  float lowest = 1e9f, highest = -1e9f;
  Vec3 centre{};
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c{(corner & 1) ? 3.0f : -1.0f, (corner & 2) ? 2.0f : 0.0f, (corner & 4) ? 1.5f : 0.5f};
    const Vec3 r = to_room(p, c);
    lowest = std::min(lowest, r.y);
    highest = std::max(highest, r.y);
    centre = centre + r * 0.125f;
  }
  EXPECT_NEAR(lowest, 0, 1e-5);                // on the STAGE floor
  EXPECT_NEAR(highest, 1.0f * p.scale, 1e-5);  // the data's up (z extent 1) is the room's up
  EXPECT_NEAR(centre.x, 0, 1e-5);
  EXPECT_NEAR(centre.z, -1.2f, 1e-5);
  // LOCAL: the origin is the head; the floor is assumed 1.6 m below.
  const Placement local = initial_placement(scene, Floor::Local);
  EXPECT_NEAR(to_room(local, {-1, 0, 0.5f}).y, -1.6f, 1e-5);
}

TEST(Placement, EyeViewIsRigidInDataUnitsAndDepthMatchesTheRoomProjection) {
  Placement placement;
  placement.pose = {axis_angle({0, 1, 0}, 0.4f), {0.2f, 0.1f, -1.0f}};
  placement.scale = 0.25f;  // 4 data units per metre
  const Pose eye{axis_angle({1, 0, 0}, -0.2f), {0.03f, 1.6f, 0.5f}};
  const Fov fov{-0.8f, 0.7f, 0.75f, -0.85f};
  const render::View v = eye_view(eye, fov, placement, 0.05f, 50.0f, {0, 0, 100, 100});
  const Vec3 data{1.0f, -2.0f, 0.5f};
  // In data units: the eye-space distance is the room distance over the scale.
  const render::Vec4 e = project(v.view, data);
  const Vec3 room_eye = transform(inverse(eye), to_room(placement, data));
  expect_near({e.x, e.y, e.z}, room_eye * (1.0f / placement.scale), 1e-4f);
  // The same clip position (x, y and depth) as a projection in metres.
  const render::Vec4 c = project(v.projection, {e.x, e.y, e.z});
  const render::Vec4 cm = project(fov_projection(fov, 0.05f, 50.0f), room_eye);
  EXPECT_NEAR(c.x / c.w, cm.x / cm.w, 1e-5);
  EXPECT_NEAR(c.y / c.w, cm.y / cm.w, 1e-5);
  EXPECT_NEAR(c.z / c.w, cm.z / cm.w, 1e-6);
}

ActionState idle() { return {}; }

HandState hand(Vec3 position, Quat orientation = {}, bool grab = true) { return {grab, true, {orientation, position}}; }

TEST(Controls, PlayPauseTogglesOncePerPress) {
  Controls c({});
  ActionState a;
  a.play_pause = true;
  EXPECT_TRUE(c.update(a, 0.01).toggle_play);
  EXPECT_FALSE(c.update(a, 0.01).toggle_play);  // still held
  EXPECT_FALSE(c.update(idle(), 0.01).toggle_play);
  EXPECT_TRUE(c.update(a, 0.01).toggle_play);
}

TEST(Controls, ScrubStepsFramesAtTheStickRate) {
  Controls c({});
  ActionState a;
  a.scrub = 1;  // full right: 30 frames per second
  int64_t frames = 0;
  for (int i = 0; i < 90; ++i) frames += c.update(a, 1.0 / 90).step;
  EXPECT_NEAR(double(frames), 30, 1);
  a.scrub = -0.625f;  // half way out beyond the dead zone (0.25): 15 frames back per second
  frames = 0;
  for (int i = 0; i < 90; ++i) frames += c.update(a, 1.0 / 90).step;
  EXPECT_NEAR(double(frames), -15, 1);
  a.scrub = 0.2f;  // inside the dead zone
  EXPECT_EQ(c.update(a, 1.0).step, 0);
  a.scrub = 0;
  a.lod = 1;
  EXPECT_NEAR(c.update(a, 0.1).lod_delta, 0.05f, 1e-6);
  a.lod = -1;
  EXPECT_NEAR(c.update(a, 0.1).lod_delta, -0.05f, 1e-6);
}

TEST(Controls, OneHandCarriesTheDataRigidly) {
  Placement start;
  start.pose.position = {0, 0, -1};
  start.scale = 0.5f;
  Controls c(start);
  const Vec3 data{1, 2, 3};
  const Pose h0{{}, {0.2f, 1.0f, -0.5f}};
  ActionState a;
  a.hands[1] = hand(h0.position);
  c.update(a, 0.01);
  const Vec3 in_hand = transform(inverse(h0), to_room(c.placement(), data));
  // The hand moves and turns: the data keeps its place in the hand.
  const Pose h1{axis_angle({0.3f, 1, 0}, 1.1f), {0.5f, 1.2f, -0.3f}};
  a.hands[1] = hand(h1.position, h1.orientation);
  EXPECT_TRUE(c.update(a, 0.01).moved);
  expect_near(transform(inverse(h1), to_room(c.placement(), data)), in_hand, 1e-5f);
  EXPECT_FLOAT_EQ(c.placement().scale, 0.5f);
  // Let go: it stays where it was put.
  const Placement put = c.placement();
  a.hands[1].grab = false;
  EXPECT_FALSE(c.update(a, 0.01).moved);
  expect_near(to_room(c.placement(), data), to_room(put, data));
  // An untracked hand does not grab.
  a.hands[0] = hand({5, 5, 5});
  a.hands[0].pose_valid = false;
  EXPECT_FALSE(c.update(a, 0.01).moved);
}

TEST(Controls, TwoHandsScaleTurnAndMoveAboutTheirMidpoint) {
  Placement start;
  start.pose.position = {0, 0, -1};
  start.scale = 1;
  Controls c(start);
  ActionState a;
  a.hands[0] = hand({-0.2f, 1, -0.5f});
  a.hands[1] = hand({0.2f, 1, -0.5f});
  c.update(a, 0.01);
  const Vec3 mid0{0, 1, -0.5f};
  // The data point under the hands' midpoint.
  const Vec3 at_mid = transform(inverse(start.pose), mid0);
  // Hands twice as far apart, the line between them turned 90 degrees about
  // the vertical, and the pair moved up by 0.1.
  a.hands[0] = hand({0, 1.1f, -0.1f});
  a.hands[1] = hand({0, 1.1f, -0.9f});
  c.update(a, 0.01);
  EXPECT_NEAR(c.placement().scale, 2, 1e-5);
  const Vec3 mid1{0, 1.1f, -0.5f};
  expect_near(to_room(c.placement(), at_mid), mid1, 1e-5f);
  // A data direction that pointed along +x (the line between the hands) now points along -z.
  const Vec3 dx = to_room(c.placement(), at_mid + Vec3{1, 0, 0}) - mid1;
  expect_near(dx, {0, 0, -2}, 1e-4f);
  // One hand lets go: nothing jumps, the other carries on alone.
  const Placement held = c.placement();
  a.hands[0].grab = false;
  c.update(a, 0.01);
  expect_near(to_room(c.placement(), at_mid), to_room(held, at_mid), 1e-5f);
  EXPECT_NEAR(c.placement().scale, 2, 1e-5);
}

}  // namespace
}  // namespace sluice::xr
