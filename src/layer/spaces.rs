//! Reference spaces: the layer's own VIEW and LOCAL spaces per session (created at
//! xrCreateSession, destroyed before the app's xrDestroySession is forwarded), locating one
//! space in another (the app's own spaces and their types, for captures: app_spaces.rs).

use super::dispatch::NextFns;
use crate::algorithm::registration::Pose;
use glam::{DQuat, DVec3};
use openxr_sys as xr;

/// The layer's own spaces of one session.
#[derive(Clone, Copy, Debug)]
pub struct Spaces {
    pub view: xr::Space,
    pub local: xr::Space,
}

fn reference_space(
    next: &NextFns,
    session: xr::Session,
    ty: xr::ReferenceSpaceType,
) -> Option<xr::Space> {
    let info = xr::ReferenceSpaceCreateInfo {
        ty: xr::StructureType::REFERENCE_SPACE_CREATE_INFO,
        next: std::ptr::null(),
        reference_space_type: ty,
        pose_in_reference_space: xr::Posef::IDENTITY,
    };
    let mut space = xr::Space::NULL;
    // SAFETY: a valid create info and out pointer for a session the runtime created.
    let r = unsafe { (next.create_reference_space)(session, &info, &mut space) };
    (r == xr::Result::SUCCESS).then_some(space)
}

/// Creates the session's VIEW and LOCAL spaces (None, said once, if the runtime refuses).
pub fn create(next: &NextFns, session: xr::Session) -> Option<Spaces> {
    let view = reference_space(next, session, xr::ReferenceSpaceType::VIEW);
    let local = reference_space(next, session, xr::ReferenceSpaceType::LOCAL);
    match (view, local) {
        (Some(view), Some(local)) => Some(Spaces { view, local }),
        (view, local) => {
            for s in [view, local].into_iter().flatten() {
                // SAFETY: a space the layer created and nothing else uses.
                unsafe { (next.destroy_space)(s) };
            }
            super::log::once(
                "no-spaces",
                "cannot create VIEW and LOCAL reference spaces: the background stays head-fixed",
            );
            None
        }
    }
}

pub fn destroy(next: &NextFns, spaces: Spaces) {
    for s in [spaces.view, spaces.local] {
        // SAFETY: spaces the layer created; no other thread uses them.
        unsafe { (next.destroy_space)(s) };
    }
}

/// `space` in `base` at `time`, when both its orientation and position are valid.
pub fn locate(next: &NextFns, space: xr::Space, base: xr::Space, time: xr::Time) -> Option<Pose> {
    let mut location = xr::SpaceLocation {
        ty: xr::StructureType::SPACE_LOCATION,
        next: std::ptr::null_mut(),
        location_flags: xr::SpaceLocationFlags::EMPTY,
        pose: xr::Posef::IDENTITY,
    };
    // SAFETY: valid handles of one session and a valid out struct.
    let r = unsafe { (next.locate_space)(space, base, time, &mut location) };
    let valid = xr::SpaceLocationFlags::ORIENTATION_VALID | xr::SpaceLocationFlags::POSITION_VALID;
    (r == xr::Result::SUCCESS && location.location_flags.contains(valid))
        .then(|| pose_of(&location.pose))
}

pub fn pose_of(p: &xr::Posef) -> Pose {
    let (o, q) = (p.position, p.orientation);
    Pose {
        position: DVec3::new(f64::from(o.x), f64::from(o.y), f64::from(o.z)),
        orientation: DQuat::from_xyzw(
            f64::from(q.x),
            f64::from(q.y),
            f64::from(q.z),
            f64::from(q.w),
        )
        .normalize(),
    }
}
