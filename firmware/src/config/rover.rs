//! Capacities, budgets and the default Axel-class parameters for [`crate::rover`] (Paton et al. section IV-A).
//!
//! Sources: Nesnas et al., "Axel and DuAxel rovers for the sustainable exploration of extreme terrains", JFR 2012
//! (two-wheeled rover, central body with a trailing boom that carries the tether exit, grouser wheels); Paton et al.
//! 2020 (12 contact points per wheel, body collision points along the axle, boom inline / in contact). Where the
//! papers give no number the value is an assumption, marked so.

/// Contact points per rim circle. Default 12 (Paton et al. IV-A: "a circle of 12 contact points").
pub const WHEEL_RIM_POINTS: usize = 12;
/// Rim circles per wheel: the wheel is a cylinder of width `wheel_width_m`, and what it touches first is on one of
/// its two edge circles (a plane, an edge, a rock's flank beside it). Default 2.
pub const WHEEL_RIMS: usize = 2;
/// Contact points per wheel: `WHEEL_RIMS` circles of `WHEEL_RIM_POINTS`. Default 24.
pub const WHEEL_CONTACT_POINTS: usize = WHEEL_RIMS * WHEEL_RIM_POINTS;
/// Steps of the rim search either side of a wheel's lowest contact point, over half a point spacing, for the rim
/// point nearest the surface (`rover` module docs, step 5). Default 8 (1.9 degree steps over +-15 degrees).
pub const RIM_REFINE_STEPS: u32 = 8;
/// Body collision points along the axle (rover Y axis) between the wheels. Default 9 (assumption: one every
/// ~10 cm over the 0.8 m between the wheels' inner faces).
pub const BODY_COLLISION_POINTS: usize = 9;
/// Settling iterations (each: one drop along the normal and one roll search). Default 24.
pub const SETTLE_MAX_ITERATIONS: u32 = 24;
/// Sphere-tracing steps per drop. Default 64 (each step moves by the ESDF distance, so flat ground needs 1-3).
pub const SETTLE_MAX_DROP_STEPS: u32 = 64;
/// Discrete roll perturbations tried on each side per roll search. Default 60 (with 0.5 degree steps: +-30 degrees).
pub const SETTLE_ROLL_STEPS: i32 = 60;
/// Boom angles tried when sweeping the boom into ground contact. Default 180 (2 degree steps over a full turn).
pub const BOOM_SWEEP_STEPS: u32 = 180;

/// Points along a buried boom searched for where it enters the terrain (`rover::boom_in_contact`). Default 32
/// (3 cm apart on the 1 m boom of `RoverParams::AXEL`).
pub const BOOM_ENTRY_STEPS: u32 = 32;

/// Footprint sample points for the surface normal (a ring of this many points plus the centre). Default 8.
pub const FOOTPRINT_POINTS: usize = 8;

/// Axel-class rover parameters (all SI units). `AXEL` holds the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoverParams {
    /// Wheel radius. Default 0.35 m (0.7 m wheels; Axel's wheels are ~0.7-0.8 m across, JFR 2012).
    pub wheel_radius_m: f32,
    /// Wheel width along the axle (rim to rim). Default 0.10 m (assumption: Axel-class wheel, grousers not
    /// modelled; the physics judge's wheels are cylinders of the same width).
    pub wheel_width_m: f32,
    /// Distance between the wheel mid-planes along the axle. Default 1.0 m (assumption, Axel class).
    pub track_m: f32,
    /// Radius of the central body cylinder around the axle. Default 0.15 m (assumption).
    pub body_radius_m: f32,
    /// Boom length from the axle to the tether exit orifice. Default 1.0 m (assumption, Axel's trailing arm).
    pub boom_length_m: f32,
    /// Mass 1: wheels, central body and payload, at the axle centre. Default 40 kg (assumption).
    pub body_mass_kg: f32,
    /// Mass 2: the boom, at half its length. Default 10 kg (assumption).
    pub boom_mass_kg: f32,
    /// Wheel-terrain friction coefficient (Coulomb cone; the stability LP inscribes an octagon). Default 0.6 (assumption: compact regolith, grousers).
    pub wheel_mu: f32,
    /// Wheel contact moment coefficient about the rolling direction and the normal (Paton eqs. 4, 6), metres.
    /// Default 0.05 m (assumption: half the rim's 0.1 m width). A rigid rim's line contact carries no moment about
    /// the axle (eq. 5), whatever this is (`stability::Contact::line`).
    pub wheel_mu_m: f32,
    /// Boom-tip friction coefficient (point contact, no moment). Default 0.4 (assumption).
    pub boom_mu: f32,
    /// Largest tether tension the winch holds. Default 2000 N (assumption; ~10 rover weights on Mars).
    pub tether_max_tension_n: f32,
    /// Gravity, m/s^2 (downward along -z). Default 3.71 (Mars).
    pub gravity_mps2: f32,
    /// Settling start offset along the normal (Paton's delta). Default 0.8 m (above the 0.7 m wheel).
    pub settle_delta_m: f32,
    /// Distance at which a contact point counts as touching the surface. Default 0.01 m.
    pub contact_threshold_m: f32,
    /// Roll perturbation step. Default 0.5 degrees.
    pub roll_step_rad: f32,
    /// Body collision clearance: a collision point closer than `body_radius_m + this` to the terrain is a
    /// collision. Default 0.02 m.
    pub body_clearance_m: f32,
    /// Largest drop below the query point before settling reports "no ground". Default 1.5 m.
    pub max_drop_m: f32,
    /// Points of the footprint ring (of `FOOTPRINT_POINTS`) that may lie in unobserved space, left out of the
    /// surface normal. Default 0 (Paton et al.: unknown space is unsafe); the navigator allows half the ring
    /// (`nav`: far from the sensor, rays leave unobserved stripes that a 0.5 m ring often crosses).
    pub footprint_unobserved_max: u32,
}

impl RoverParams {
    /// The default Axel-class rover.
    pub const AXEL: RoverParams = RoverParams {
        wheel_radius_m: 0.35,
        wheel_width_m: 0.10,
        track_m: 1.0,
        body_radius_m: 0.15,
        boom_length_m: 1.0,
        body_mass_kg: 40.0,
        boom_mass_kg: 10.0,
        wheel_mu: 0.6,
        wheel_mu_m: 0.05,
        boom_mu: 0.4,
        tether_max_tension_n: 2000.0,
        gravity_mps2: 3.71,
        settle_delta_m: 0.8,
        contact_threshold_m: 0.01,
        roll_step_rad: 0.5 * core::f32::consts::PI / 180.0,
        body_clearance_m: 0.02,
        max_drop_m: 1.5,
        footprint_unobserved_max: 0,
    };
}
