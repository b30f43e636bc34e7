//! Pose helpers over [`Rot3`] / [`Pose3`](super::Pose3). The protocol's wire pose becomes a [`Pose3`](super::Pose3)
//! in one place, `protocol::Pose::to_isometry` (this layer sits below `protocol` and does not know its types).

use super::{Real, Rot3, Vec3};

/// Heading (yaw) of a rotation: the angle of its x axis projected on the horizontal plane, radians in `(-pi, pi]`.
pub fn heading(rotation: &Rot3) -> Real {
    let x = rotation * Vec3::x();
    libm::atan2f(x.y, x.x)
}
