//! Geometry helpers over `nalgebra` (no_std, `libm` backed).
//!
//! The 3D map, rover and tether work in `f32` ([`Real`]): the map's resolution (centimetres) is far coarser than
//! `f32`'s precision over a few hundred metres, and the Cortex-M7 has a single-precision FPU.
//!
//! - [`p3`]: helpers over plain `[f64; 3]` points (`sub`, `dot`, `cross`, `norm`, `dist`, `lerp`, ...), for the
//!   code that works in `f64` arrays (the workloads, the simulator's worlds, the team simulation).
//! - [`angle`]: angle wrapping ([`wrap_angle`], [`angle_diff`]).
//! - [`pose`]: rotations and poses ([`heading`]); the protocol's wire pose becomes a [`Pose3`] in
//!   `protocol::Pose::to_isometry`, the one conversion (this layer sits below `protocol`).

pub mod angle;
pub mod p3;
pub mod pose;

pub use angle::{angle_diff, wrap_angle};
pub use pose::heading;

/// The scalar of the 3D world model.
pub type Real = f32;
/// A point or vector in 3D, metres (world frame: x east, y north, z up).
pub type Vec3 = nalgebra::Vector3<Real>;
/// A unit quaternion (orientation).
pub type Rot3 = nalgebra::UnitQuaternion<Real>;
/// A rigid transform, SE(3).
pub type Pose3 = nalgebra::Isometry3<Real>;
/// A point or vector in 2D (on a plane), metres.
pub type Vec2 = nalgebra::Vector2<Real>;

/// True when every component is finite (not NaN, not infinite).
pub fn is_finite3(v: &Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// `x` limited to `[lo, hi]`: the result of `Real::clamp` whenever that does not panic (`lo <= hi`, neither NaN;
/// a NaN `x` stays NaN), and no panic path when the bounds come from a configuration that could break that rule
/// (then `lo` wins below, `hi` above). The flight build is proven free of reachable panics (`.ci/run`), and
/// `clamp`'s bounds assertion survives optimisation wherever the bounds are not constants.
pub fn clamp(x: Real, lo: Real, hi: Real) -> Real {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `libm::floorf(x) as i32` without the software floor (on x86_64 and the Cortex-M7 alike `libm` computes it
/// with integer bit operations; a truncating conversion is one instruction): `x` truncated towards zero, one less
/// when that is above `x`. Equal to `floorf(x) as i32` for every `x`, saturating as the cast does (NaN gives 0).
#[inline]
pub fn floor_i32(x: Real) -> i32 {
    let t = x as i32;
    if (t as Real) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `libm::roundf(x) as i32` (halves away from zero) without the software round, which costs ~70 instructions on
/// x86_64 and the Cortex-M7 alike: `x` truncated towards zero, moved one away from zero when the rest is at least
/// a half. The rest `x - trunc(x)` is exact in `f32`, so this equals `roundf(x) as i32` for every `x`, saturating as
/// the cast does (NaN gives 0).
#[inline]
pub fn round_i32(x: Real) -> i32 {
    let t = x as i32;
    let rest = x - t as Real;
    if rest >= 0.5 {
        t.saturating_add(1)
    } else if rest <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// Euclidean norm through `libm` (bit-identical on every target).
pub fn norm3(v: &Vec3) -> Real {
    libm::sqrtf(v.x * v.x + v.y * v.y + v.z * v.z)
}

/// `v / |v|`, or `None` when `|v|` is below `eps` or not finite.
pub fn normalize3(v: &Vec3, eps: Real) -> Option<Vec3> {
    let n = norm3(v);
    if n.is_finite() && n > eps {
        Some(v / n)
    } else {
        None
    }
}

/// Measure (volume) of the unit ball in R^n, `pi^(n/2) / Gamma(n/2 + 1)` (through `libm`).
pub fn unit_ball_measure(n: usize) -> f64 {
    let half = n as f64 / 2.0;
    libm::pow(core::f64::consts::PI, half) / libm::tgamma(half + 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_i32_is_libm_floor_cast_everywhere() {
        let specials = [
            0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1.0 - f32::EPSILON, -1.0 + f32::EPSILON, 16_777_215.5, -16_777_215.5,
            16_777_217.0, 2_147_483_520.0, 2_147_483_648.0, -2_147_483_648.0, -2_147_483_904.0, 1e30, -1e30,
            f32::MIN_POSITIVE, -f32::MIN_POSITIVE, f32::INFINITY, f32::NEG_INFINITY, f32::NAN,
        ];
        same_everywhere(&specials, floor_i32, |x| libm::floorf(x) as i32);
    }

    /// `ours(x) == reference(x)` for each of `specials` and every 997th bit pattern of the whole f32 line.
    fn same_everywhere(specials: &[f32], ours: impl Fn(f32) -> i32, reference: impl Fn(f32) -> i32) {
        let mut bits: u32 = 0;
        let patterns = core::iter::from_fn(|| {
            let x = f32::from_bits(bits);
            bits = bits.checked_add(997)?;
            Some(x)
        });
        for x in specials.iter().copied().chain(patterns) {
            assert_eq!(ours(x), reference(x), "x = {x:e}");
        }
    }

    #[test]
    fn round_i32_is_libm_round_cast_everywhere() {
        let specials = [
            0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.5 - f32::EPSILON / 2.0, -0.5 + f32::EPSILON / 2.0,
            8_388_607.5, -8_388_607.5, 8_388_609.0, 16_777_217.0, 2_147_483_520.0, 2_147_483_648.0,
            -2_147_483_648.0, -2_147_483_904.0, 1e30, -1e30, f32::MIN_POSITIVE, f32::INFINITY, f32::NEG_INFINITY,
            f32::NAN,
        ];
        same_everywhere(&specials, round_i32, |x| libm::roundf(x) as i32);
    }

    #[test]
    fn normalize_rejects_zero_and_nan() {
        assert!(normalize3(&Vec3::zeros(), 1e-6).is_none());
        assert!(normalize3(&Vec3::new(Real::NAN, 0.0, 0.0), 1e-6).is_none());
        let u = normalize3(&Vec3::new(3.0, 0.0, 4.0), 1e-6);
        assert_eq!(u.map(|u| norm3(&u)), Some(1.0));
    }

    #[test]
    fn clamp_equals_the_core_clamp_where_that_does_not_panic_and_never_panics() {
        let xs = [-2.0, -1.0, -0.5, 0.0, 0.25, 1.0, 3.0, Real::INFINITY, Real::NEG_INFINITY];
        for (lo, hi) in [(-1.0, 1.0), (0.0, 0.0), (0.0, 2.5), (Real::NEG_INFINITY, 0.0)] {
            for x in xs {
                assert_eq!(clamp(x, lo, hi).to_bits(), x.clamp(lo, hi).to_bits(), "{x} in [{lo}, {hi}]");
            }
            assert!(clamp(Real::NAN, lo, hi).is_nan());
        }
        // Bounds `Real::clamp` would panic on (lo > hi, NaN): a value, no panic.
        assert_eq!(clamp(5.0, 1.0, -1.0), -1.0);
        assert_eq!(clamp(-5.0, 1.0, -1.0), 1.0);
        assert_eq!(clamp(0.5, Real::NAN, 1.0), 0.5);
        assert_eq!(clamp(2.0, 0.0, Real::NAN), 2.0);
    }
}
