//! Helpers over plain `[f64; 3]` points and vectors ([`P3`]), for the code that works in `f64` arrays rather than
//! [`Vec3`](super::Vec3): the workloads' and the simulator's ground-truth worlds, the team simulation, the tests.
//!
//! Each helper is the plain component expression, evaluated left to right (`dot` is `a0 b0 + a1 b1 + a2 b2`);
//! square roots go through `libm` (correctly rounded, as `f64::sqrt` is, so the two agree bit for bit).

use super::{Real, Vec3};

/// A point or vector in `f64`, metres.
pub type P3 = [f64; 3];

/// As a [`Vec3`] (each component rounded to the nearest `f32`).
pub fn to_vec3(p: P3) -> Vec3 {
    Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real)
}

/// From a [`Vec3`] (exact: every `f32` is an `f64`).
pub fn from_vec3(v: &Vec3) -> P3 {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// `a - b`.
pub fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + b`.
pub fn add(a: P3, b: P3) -> P3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a * s`.
pub fn scale(a: P3, s: f64) -> P3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// `a + b * s`.
pub fn add_scaled(a: P3, b: P3, s: f64) -> P3 {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}

/// `a . b`.
pub fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `a x b`.
pub fn cross(a: P3, b: P3) -> P3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `|a|`, `sqrt(a . a)`.
pub fn norm(a: P3) -> f64 {
    libm::sqrt(dot(a, a))
}

/// `|a - b|`.
pub fn dist(a: P3, b: P3) -> f64 {
    norm(sub(a, b))
}

/// `a / |a|` (as `a * (1 / |a|)`), or `fallback` when `|a|` is not positive.
pub fn unit_or(a: P3, fallback: P3) -> P3 {
    let n = norm(a);
    if n > 0.0 {
        scale(a, 1.0 / n)
    } else {
        fallback
    }
}

/// `a + t (b - a)`.
pub fn lerp(a: P3, b: P3, t: f64) -> P3 {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])]
}

/// Component-wise minimum.
pub fn min(a: P3, b: P3) -> P3 {
    [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])]
}

/// Component-wise maximum.
pub fn max(a: P3, b: P3) -> P3 {
    [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrt_of_libm_and_std_agree() {
        let mut x = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..10_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x & 0x7fef_ffff_ffff_ffff);
            assert_eq!(libm::sqrt(v).to_bits(), v.sqrt().to_bits());
        }
    }

    #[test]
    fn helpers() {
        let (a, b) = ([1.0, 2.0, 2.0], [0.0, 0.0, 1.0]);
        assert_eq!(norm(a), 3.0);
        assert_eq!(dist(a, b), libm::sqrt(6.0));
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        assert_eq!(unit_or([0.0; 3], b), b);
        assert_eq!(lerp(a, b, 0.5), [0.5, 1.0, 1.5]);
        assert_eq!(add_scaled(a, b, 2.0), [1.0, 2.0, 4.0]);
    }
}
