//! Angle wrapping (`f32`, through `libm`).

use super::Real;

/// `a` wrapped to `(-pi, pi]`: `fmod(a, 2 pi)`, then one turn added or taken away.
pub fn wrap_angle(a: Real) -> Real {
    let tau = core::f32::consts::TAU;
    let mut d = libm::fmodf(a, tau);
    if d > core::f32::consts::PI {
        d -= tau;
    } else if d <= -core::f32::consts::PI {
        d += tau;
    }
    d
}

/// `a - b` wrapped to `(-pi, pi]`.
pub fn angle_diff(a: Real, b: Real) -> Real {
    wrap_angle(a - b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    #[test]
    fn wraps_to_half_open_interval() {
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(0.5), 0.5);
        assert_eq!(angle_diff(0.25, 0.5), -0.25);
    }
}
