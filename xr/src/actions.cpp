// The controllers: one action set, suggested bindings for four interaction
// profiles, sampled once per frame into an ActionState (controls.h).
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "session_impl.h"

namespace sluice::xr {
namespace {

XrPath path(XrInstance instance, const char* text) {
  XrPath p = XR_NULL_PATH;
  check(xrStringToPath(instance, text, &p), instance, text);
  return p;
}

XrAction make_action(XrActionSet set, XrInstance instance, const char* name, const char* label, XrActionType type,
                     const std::array<XrPath, 2>* hands) {
  XrActionCreateInfo create{XR_TYPE_ACTION_CREATE_INFO};
  create.actionType = type;
  std::snprintf(create.actionName, XR_MAX_ACTION_NAME_SIZE, "%s", name);
  std::snprintf(create.localizedActionName, XR_MAX_LOCALIZED_ACTION_NAME_SIZE, "%s", label);
  if (hands) {
    create.countSubactionPaths = 2;
    create.subactionPaths = hands->data();
  }
  XrAction a = XR_NULL_HANDLE;
  check(xrCreateAction(set, &create, &a), instance, "xrCreateAction");
  return a;
}

struct Binding {
  XrAction action;
  const char* path;
};

}  // namespace

void detail::SessionImpl::create_actions() {
  XrActionSetCreateInfo create{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::snprintf(create.actionSetName, XR_MAX_ACTION_SET_NAME_SIZE, "playback");
  std::snprintf(create.localizedActionSetName, XR_MAX_LOCALIZED_ACTION_SET_NAME_SIZE, "Playback");
  check(xrCreateActionSet(instance, &create, &action_set), instance, "xrCreateActionSet");
  hand_paths = {path(instance, "/user/hand/left"), path(instance, "/user/hand/right")};
  play_pause = make_action(action_set, instance, "play_pause", "Play / pause", XR_ACTION_TYPE_BOOLEAN_INPUT, nullptr);
  stick = make_action(action_set, instance, "scrub_lod", "Scrub (x) and level of detail (y)", XR_ACTION_TYPE_VECTOR2F_INPUT,
                      &hand_paths);
  grab = make_action(action_set, instance, "grab", "Grab the fluid", XR_ACTION_TYPE_BOOLEAN_INPUT, &hand_paths);
  grip = make_action(action_set, instance, "grip_pose", "Hand pose", XR_ACTION_TYPE_POSE_INPUT, &hand_paths);

  // Per profile: what grabs, what toggles playback, what scrubs.
  const auto suggest = [&](const char* profile, const std::vector<Binding>& bindings) {
    std::vector<XrActionSuggestedBinding> list;
    for (const Binding& b : bindings) list.push_back({b.action, path(instance, b.path)});
    XrInteractionProfileSuggestedBinding suggested{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    suggested.interactionProfile = path(instance, profile);
    suggested.countSuggestedBindings = uint32_t(list.size());
    suggested.suggestedBindings = list.data();
    check(xrSuggestInteractionProfileBindings(instance, &suggested), instance, profile);
  };
  suggest("/interaction_profiles/khr/simple_controller",
          {{grab, "/user/hand/left/input/select/click"}, {grab, "/user/hand/right/input/select/click"},
           {play_pause, "/user/hand/left/input/menu/click"}, {play_pause, "/user/hand/right/input/menu/click"},
           {grip, "/user/hand/left/input/grip/pose"}, {grip, "/user/hand/right/input/grip/pose"}});
  suggest("/interaction_profiles/oculus/touch_controller",
          {{grab, "/user/hand/left/input/squeeze/value"}, {grab, "/user/hand/right/input/squeeze/value"},
           {play_pause, "/user/hand/left/input/x/click"}, {play_pause, "/user/hand/right/input/a/click"},
           {stick, "/user/hand/left/input/thumbstick"}, {stick, "/user/hand/right/input/thumbstick"},
           {grip, "/user/hand/left/input/grip/pose"}, {grip, "/user/hand/right/input/grip/pose"}});
  suggest("/interaction_profiles/valve/index_controller",
          {{grab, "/user/hand/left/input/squeeze/value"}, {grab, "/user/hand/right/input/squeeze/value"},
           {play_pause, "/user/hand/left/input/a/click"}, {play_pause, "/user/hand/right/input/a/click"},
           {stick, "/user/hand/left/input/thumbstick"}, {stick, "/user/hand/right/input/thumbstick"},
           {grip, "/user/hand/left/input/grip/pose"}, {grip, "/user/hand/right/input/grip/pose"}});
  suggest("/interaction_profiles/htc/vive_controller",
          {{grab, "/user/hand/left/input/squeeze/click"}, {grab, "/user/hand/right/input/squeeze/click"},
           {play_pause, "/user/hand/left/input/menu/click"}, {play_pause, "/user/hand/right/input/menu/click"},
           {stick, "/user/hand/left/input/trackpad"}, {stick, "/user/hand/right/input/trackpad"},
           {grip, "/user/hand/left/input/grip/pose"}, {grip, "/user/hand/right/input/grip/pose"}});
}

void detail::SessionImpl::attach_actions() {
  XrSessionActionSetsAttachInfo attach{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  attach.countActionSets = 1;
  attach.actionSets = &action_set;
  check(xrAttachSessionActionSets(session, &attach), instance, "xrAttachSessionActionSets");
  for (size_t h = 0; h < 2; ++h) {
    XrActionSpaceCreateInfo space_info{XR_TYPE_ACTION_SPACE_CREATE_INFO};
    space_info.action = grip;
    space_info.subactionPath = hand_paths[h];
    space_info.poseInActionSpace.orientation.w = 1;
    check(xrCreateActionSpace(session, &space_info, &grip_spaces[h]), instance, "xrCreateActionSpace");
  }
}

void detail::SessionImpl::destroy_action_spaces() {
  for (XrSpace& s : grip_spaces) {
    if (s) xrDestroySpace(s);
    s = XR_NULL_HANDLE;
  }
}

ActionState detail::SessionImpl::sample_actions(XrTime time) {
  ActionState a;
  if (state != State::Focused) return a;  // input goes to whoever has focus
  const XrActiveActionSet active{action_set, XR_NULL_PATH};
  XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  check(xrSyncActions(session, &sync), instance, "xrSyncActions");

  XrActionStateGetInfo get{XR_TYPE_ACTION_STATE_GET_INFO};
  XrActionStateBoolean boolean{XR_TYPE_ACTION_STATE_BOOLEAN};
  get.action = play_pause;
  check(xrGetActionStateBoolean(session, &get, &boolean), instance, "xrGetActionStateBoolean");
  a.play_pause = boolean.isActive && boolean.currentState;
  for (size_t h = 0; h < 2; ++h) {
    get.subactionPath = hand_paths[h];
    get.action = stick;
    XrActionStateVector2f v{XR_TYPE_ACTION_STATE_VECTOR2F};
    check(xrGetActionStateVector2f(session, &get, &v), instance, "xrGetActionStateVector2f");
    if (v.isActive) {
      a.scrub += v.currentState.x;
      a.lod += v.currentState.y;
    }
    get.action = grab;
    boolean = {XR_TYPE_ACTION_STATE_BOOLEAN};
    check(xrGetActionStateBoolean(session, &get, &boolean), instance, "xrGetActionStateBoolean");
    a.hands[h].grab = boolean.isActive && boolean.currentState;
    XrSpaceLocation location{XR_TYPE_SPACE_LOCATION};
    check(xrLocateSpace(grip_spaces[h], space, time, &location), instance, "xrLocateSpace");
    const XrSpaceLocationFlags needed = XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
    a.hands[h].pose_valid = (location.locationFlags & needed) == needed;
    const XrPosef& p = location.pose;
    a.hands[h].grip = {{p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}, {p.position.x, p.position.y, p.position.z}};
  }
  a.scrub = std::max(-1.0f, std::min(1.0f, a.scrub));
  a.lod = std::max(-1.0f, std::min(1.0f, a.lod));
  return a;
}

}  // namespace sluice::xr
