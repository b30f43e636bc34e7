//! The physical judge: Axel as rigid bodies on the exact terrain in a real rigid-body engine (rapier3d-f64 0.36
//! with `enhanced-determinism`), independent of the flight software's rover model (`firmware::rover` settling,
//! `firmware::stability`'s LP, Paton et al. IV-A and IV-C): nothing here calls it, and nothing here reads a
//! distance field.
//!
//! # The rover (Paton et al. IV-A's Axel, dimensions and masses from `RoverParams`)
//! - Two **wheels**: each a plain cylinder of radius `wheel_radius_m` (0.35 m) and width [`WHEEL_WIDTH_M`]
//!   (0.10 m, an assumption: the grousers are not modelled, their grip is in the friction coefficient; the
//!   planner's `RoverParams::wheel_width_m` states the same width on the flight side), centred
//!   at `+-track_m / 2` (0.5 m) on the axle, each its own rigid body on a revolute joint about the axle. Mass
//!   [`WHEEL_MASS_KG`] = 10 kg each.
//! - The **body**: a cylinder of radius `body_radius_m` (0.15 m) around the axle between the wheels (1 cm gap to
//!   each), mass `body_mass_kg` - 2 x 10 kg = 20 kg, so the three carry the model's 40 kg at the axle centre.
//! - The **boom**: a capsule of radius [`BOOM_RADIUS_M`] (3 cm) from the axle to its tip at `boom_length_m`
//!   (1 m), rigid with the body (the boom motor holds it), mass `boom_mass_kg` (10 kg) spread along it (centre of
//!   mass at half its length, as in the planner's model). The tether leaves from the tip.
//! - Friction: a wheel-terrain contact has the scenario's `wheel_mu` (0.6), a boom-terrain or body-terrain
//!   contact `boom_mu` (0.4); the terrain's own coefficient is 1 and the rover's colliders combine by product.
//! - Gravity `gravity_mps2` (3.71 m/s^2) along -z.
//!
//! # The tether
//! A rope joint (a maximum distance, no stiffness below it) from a fixed point at the **true** last anchor
//! (from [`crate::truth::taut`], never from `firmware::tether`) to the boom tip; its length is the payout beyond
//! that anchor, the winch locked. `None` for the free length: taut at the placed pose.
//!
//! # Placing a pose
//! [`PhysicsJudge::place`]: `yaw` is the heading of the rolling direction, as the flight software's; the axle is
//! horizontal across the frame's yaw that makes it so on the local ground ([`PhysicsJudge::frame_yaw`]) and rolled
//! so both wheels rest at their own ground
//! height (ray casts under each wheel, then each wheel's cylinder cast straight down onto the terrain,
//! [`PLACE_ROUNDS`] rounds), [`PLACE_GAP_M`] (2 mm) above the first touch. Where the rounds leave one wheel in
//! the air (a wheel over a ledge's lip: the ground under its centre is far below where its rim rests), the rover is
//! lowered level and pivoted about the wheel that touches first until the other touches (the roll bracketed in
//! [`PLACE_PIVOT_STEP_DEG`] steps, then bisected); a pose with no such roll within 80 degrees is blocked. The boom
//! points at the anchor (inline, Paton IV-A) or is swept from there in 1-degree steps (refined to 0.01 degrees)
//! until it touches the terrain (resting); an inline boom that overlaps the terrain is raised in 1-degree steps
//! until clear (at most 180). A pose whose wheels or body overlap the terrain after placement, or whose boom finds
//! no clear angle, is [`HoldOutcome::Blocked`].
//!
//! # Hold test ([`PhysicsJudge::hold`])
//! The rover chooses its boom angle (as the planner tries inline and in contact): the boom settings of
//! [`BOOM_SETTINGS`] are tried in turn — inline, then swept from the inline angle onto the terrain the way that
//! lowers the tip, then the other way — and the pose holds if one of them holds. For each: brakes on (each wheel's
//! joint locked at its angle), the rover is released at the placed pose and simulated for
//! [`HOLD_SECONDS`] = 3 s at [`STEP_HZ`] = 240 steps per second. It **holds** iff over the whole run
//! - the axle centre moves less than [`HOLD_SLIDE_M`] = 5 cm: one step of the campaign's 5 cm interpolation, and a
//!   seventh of the wheel radius; a rover that moves more has left the pose the plan claims (the settling
//!   drop of the 2 mm gap is far below it);
//! - the axle direction turns by less than [`HOLD_TILT_DEG`] = 5 degrees: a wheel lifts off by `track sin 5 deg`
//!   = 8.7 cm, a quarter of the wheel radius, before that — the rover is no longer standing on both wheels, which
//!   every planner pose assumes (the body turning about the axle is not tilt: Axel's body rotates about its
//!   axle by design);
//! - and at the end the axle moves slower than [`HOLD_END_SPEED_MPS`] = 1 cm/s (not a slow slide that the 3 s
//!   window cut short).
//!
//! # Drive test ([`PhysicsJudge::drive`])
//! A straight drive or a turn in place executed dynamically: wheel joints driven by velocity motors (straight:
//! both wheels at `speed / r`; turn: opposite at `rate * track / 2 / r`) until the wheels' odometry reaches the
//! command, then the brakes for [`DRIVE_SETTLE_SECONDS`] = 1 s. The boom setting is the first of
//! [`BOOM_SETTINGS`] that holds at the start (inline if none does). The winch keeps the tether taut: the rope
//! shortens to the anchor-tip distance when the rover comes closer and pays out no faster than the wheels roll.
//! It reports the end pose and whether the rover **fell**: the axle turned more than [`FALL_TILT_DEG`] = 30
//! degrees out of its starting plane at any time, or the rover had not come to rest (speed above 1 cm/s) after
//! the brakes. The budget is [`DRIVE_MAX_SECONDS`] of simulated time per metre or radian commanded.
//!
//! # Determinism
//! Every test builds a fresh rapier world from the same shapes in the same order; `enhanced-determinism` makes
//! rapier's arithmetic identical run to run and machine to machine, so a verdict is a pure function of its inputs.

pub mod path;
pub mod terrain;

use rapier3d_f64::prelude::*;

use firmware::config::rover::RoverParams;
use firmware::geom::p3::P3;
use terrain::{p3, v3, PhysicsTerrain, TerrainError};

use crate::world::World;

/// Wheel width (assumption, see the module docs), metres.
pub const WHEEL_WIDTH_M: f64 = 0.10;
/// Mass of one wheel (part of `body_mass_kg`), kg.
pub const WHEEL_MASS_KG: f64 = 10.0;
/// Boom capsule radius, metres.
pub const BOOM_RADIUS_M: f64 = 0.03;
/// Gap above the terrain at which a pose is placed, metres.
pub const PLACE_GAP_M: f64 = 0.002;
/// Rounds of re-rolling the axle through both wheels' touch heights when placing a pose.
pub const PLACE_ROUNDS: usize = 4;
/// The wheels rest together when their drops differ by at most this after the rounds, metres; otherwise the
/// placement pivots from level ([`PLACE_PIVOT_STEP_DEG`]).
pub const PLACE_ROLL_TOLERANCE_M: f64 = 1e-3;
/// Roll step of the pivot from level that brackets the roll at which both wheels touch, degrees.
pub const PLACE_PIVOT_STEP_DEG: f64 = 2.0;
/// Steps of the pivot: 40 x 2 = 80 degrees either way at most.
pub const PLACE_PIVOT_STEPS: usize = 40;
/// Bisections of the bracketed roll: 2 degrees / 2^16, about 3e-5 degrees.
pub const PLACE_PIVOT_BISECTIONS: usize = 16;
/// Bisections of [`PhysicsJudge::heading_for_axle`]: 180 degrees / 2^30, far below a millidegree.
pub const HEADING_BISECTIONS: usize = 30;
/// Simulated seconds of the hold test.
pub const HOLD_SECONDS: f64 = 3.0;
/// Simulation steps per second.
pub const STEP_HZ: f64 = 240.0;
/// Largest axle-centre motion of a pose that holds, metres.
pub const HOLD_SLIDE_M: f64 = 0.05;
/// Largest axle turn of a pose that holds, degrees.
pub const HOLD_TILT_DEG: f64 = 5.0;
/// Largest axle speed at the end of a hold, m/s.
pub const HOLD_END_SPEED_MPS: f64 = 0.01;
/// Rounds of aiming the boom at the tether and moving the tether's end to the tip ([`PhysicsJudge::aim_tether`]).
pub const AIM_ROUNDS: usize = 2;
/// The aim has settled when the last anchor moves less than this, metres.
pub const AIM_TOLERANCE_M: f64 = 1e-3;
/// Seconds braked after a drive.
pub const DRIVE_SETTLE_SECONDS: f64 = 1.0;
/// Axle turn beyond which a drive fell, degrees.
pub const FALL_TILT_DEG: f64 = 30.0;
/// Simulated seconds allowed per metre (straight) or radian (turn) commanded, plus one.
pub const DRIVE_MAX_SECONDS: f64 = 20.0;

/// Horizontal half-base of the terrain samples that give the ground normal under a pose ([`PhysicsJudge::frame_yaw`]),
/// metres. Default 0.25 m: half Axel's axle track, the scale of the wheels' own footprint.
pub const NORMAL_BASE_M: f64 = 0.25;

/// A pose to judge: the axle centre's ground position and the heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundPose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading of the rover's x axis (the rolling direction) from world x about z, radians.
    pub yaw: f64,
}

/// The tether as the judge sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetherSpec {
    /// The true last anchor (where the free tether leaves the terrain or the root), world frame.
    pub anchor: P3,
    /// Tether length from the anchor to the boom tip (the winch locked); `None`: taut at the placed pose.
    pub free_length_m: Option<f64>,
}

/// A placed rover: where the bodies start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Axle centre, world frame.
    pub axle: P3,
    /// Unit axle direction (rover +y, towards the left wheel).
    pub axle_dir: P3,
    /// Boom angle in the rover's x-z plane (0 = forward, pi = trailing), radians.
    pub boom_angle: f64,
    /// Boom tip (tether exit), world frame.
    pub tip: P3,
    /// The boom is off the inline angle (it rests on the terrain, or was raised clear of it).
    pub boom_raised: bool,
    /// The boom setting asked for.
    pub boom: BoomSetting,
    /// Yaw of the rover frame the placement was built in ([`PhysicsJudge::frame_yaw`] of the pose's heading).
    pub frame_yaw: f64,
}

/// Which way a resting boom is swept from the inline angle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sense {
    /// The way that first lowers the tip (forward booms down in front, trailing booms down behind).
    Down,
    /// The other way (over the top of the rover).
    Over,
}

/// How the boom is set for a test (Paton IV-A's two configurations; the rover chooses its boom angle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoomSetting {
    /// Pointing at the anchor.
    Inline,
    /// Swept from the inline angle until its tip rests on the terrain.
    Rest(Sense),
}

/// The boom settings [`PhysicsJudge::hold`] tries, in order.
pub const BOOM_SETTINGS: [BoomSetting; 3] = [BoomSetting::Inline, BoomSetting::Rest(Sense::Down), BoomSetting::Rest(Sense::Over)];

/// The answer of [`PhysicsJudge::hold`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HoldOutcome {
    /// The pose holds.
    Holds,
    /// The rover slid, tipped or was still moving at the end.
    Falls,
    /// No placement: no ground under a wheel, or the wheels or body overlap the terrain.
    Blocked,
}

/// The hold test's verdict with its measurements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldVerdict {
    /// Holds, falls or could not be placed.
    pub outcome: HoldOutcome,
    /// The placement (when placed).
    pub placement: Option<Placement>,
    /// Largest axle-centre motion, metres.
    pub slide_m: f64,
    /// Largest axle turn, degrees.
    pub tilt_deg: f64,
    /// Axle speed at the end, m/s.
    pub end_speed_mps: f64,
}

impl HoldVerdict {
    /// True when the pose holds.
    pub fn holds(&self) -> bool {
        self.outcome == HoldOutcome::Holds
    }
}

/// A motion for [`PhysicsJudge::drive`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveCommand {
    /// Drive straight along the heading by this distance (negative: backwards), metres, at `speed_mps`.
    Straight {
        /// Distance, metres.
        distance_m: f64,
        /// Axle speed, m/s (> 0).
        speed_mps: f64,
    },
    /// Turn in place by this angle (counter-clockwise seen from above positive), radians, at `rate_radps`.
    Turn {
        /// Angle, radians.
        angle_rad: f64,
        /// Turn rate, rad/s (> 0).
        rate_radps: f64,
    },
}

/// The answer of [`PhysicsJudge::drive`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveReport {
    /// The rover could be placed at the start (otherwise nothing else is meaningful).
    pub placed: bool,
    /// The motion fell (see the module docs).
    pub fell: bool,
    /// The command was completed by the wheels' odometry within the time budget.
    pub completed: bool,
    /// Axle centre at the end, world frame.
    pub end_axle: P3,
    /// Heading of the rolling direction at the end ([`PhysicsJudge::frame_yaw`]'s sense), radians.
    pub end_yaw: f64,
    /// Largest axle turn out of its starting plane, degrees.
    pub max_tilt_deg: f64,
    /// Simulated seconds.
    pub seconds: f64,
}

/// The judge for one world: its terrain shapes (built once) and the rover.
#[derive(Debug, Clone)]
pub struct PhysicsJudge {
    terrain: PhysicsTerrain,
    rover: RoverParams,
    z_lo: f64,
    z_hi: f64,
}

/// Handles of a rover in a rapier world.
struct RoverBodies {
    chassis: RigidBodyHandle,
    wheels: [RigidBodyHandle; 2],
    wheel_joints: [ImpulseJointHandle; 2],
    rope: Option<ImpulseJointHandle>,
}

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: P3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}
fn angle_between(a: Vector, b: Vector) -> f64 {
    a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos()
}

impl PhysicsJudge {
    /// The judge of `world` for `rover`.
    pub fn new(world: &dyn World, rover: RoverParams) -> Result<PhysicsJudge, TerrainError> {
        let terrain = PhysicsTerrain::new(&world.exact_geometry())?;
        let b = world.bounds();
        Ok(PhysicsJudge { terrain, rover, z_lo: f64::from(b.min.z) - 50.0, z_hi: f64::from(b.max.z) + 50.0 })
    }

    /// The terrain shapes.
    pub fn terrain(&self) -> &PhysicsTerrain {
        &self.terrain
    }

    fn r(&self) -> f64 {
        f64::from(self.rover.wheel_radius_m)
    }
    fn half_track(&self) -> f64 {
        0.5 * f64::from(self.rover.track_m)
    }

    /// The rover's rotation for heading `yaw`, axle roll `roll` (about the rover x axis) and body pitch 0.
    fn rotation(yaw: f64, roll: f64) -> Rotation {
        Rotation::from_axis_angle(Vector::Z, yaw) * Rotation::from_axis_angle(Vector::X, roll)
    }

    fn wheel_shape(&self) -> SharedShape {
        SharedShape::cylinder(0.5 * WHEEL_WIDTH_M, self.r())
    }

    /// Place the rover at `pose` with its boom set by `boom` relative to `anchor` (see the module docs). `None`:
    /// no ground, the wheels or body overlap the terrain, or no boom angle of that setting is clear.
    pub fn place(&self, pose: GroundPose, anchor: P3, boom: BoomSetting) -> Option<Placement> {
        let frame_yaw = self.frame_yaw(pose);
        let (rot, axle) = self.place_wheels(pose, frame_yaw)?;
        let ay = rot * Vector::Y;
        let body = Pose::from_parts(axle, rot);
        let l = f64::from(self.rover.boom_length_m);
        let boom_clear = |beta: f64| {
            let tip_local = Vector::new(l * beta.cos(), 0.0, l * beta.sin());
            !self.terrain.intersects(&body, &Capsule::new(Vector::ZERO, tip_local, BOOM_RADIUS_M))
        };
        let to_anchor = rot.inverse() * (v3(anchor) - axle);
        let inline = to_anchor.z.atan2(to_anchor.x);
        let step = 1f64.to_radians();
        let (beta, raised) = if !boom_clear(inline) {
            // The inline boom is buried: raise it (towards the vertical on its side) until clear.
            let up = if inline.cos() >= 0.0 { 1.0 } else { -1.0 };
            let k = (1..=180).find(|&k| boom_clear(inline + up * k as f64 * step))?;
            (inline + up * k as f64 * step, true)
        } else {
            match boom {
                BoomSetting::Inline => (inline, false),
                BoomSetting::Rest(sense) => {
                    // Sweep from the inline angle until the boom first touches; keep the last clear angle,
                    // refined by bisection to 0.01 degrees. A boom that never touches has no rest here.
                    let dir = match sense {
                        Sense::Down => if inline.cos() >= 0.0 { -1.0 } else { 1.0 },
                        Sense::Over => if inline.cos() >= 0.0 { 1.0 } else { -1.0 },
                    };
                    let k = (1..=360).find(|&k| !boom_clear(inline + dir * k as f64 * step))?;
                    let (mut lo, mut hi) = ((k - 1) as f64 * step, k as f64 * step);
                    for _ in 0..7 {
                        let m = 0.5 * (lo + hi);
                        if boom_clear(inline + dir * m) {
                            lo = m
                        } else {
                            hi = m
                        }
                    }
                    (inline + dir * lo, true)
                }
            }
        };
        let tip = axle + rot * Vector::new(l * beta.cos(), 0.0, l * beta.sin());
        Some(Placement { axle: p3(axle), axle_dir: p3(ay), boom_angle: beta, tip: p3(tip), boom_raised: raised, boom, frame_yaw })
    }

    /// The axle centre of the rover set down at `pose` (its wheels on the terrain), `None` as in [`Self::place`].
    pub fn axle_at(&self, pose: GroundPose) -> Option<P3> {
        self.place_wheels(pose, self.frame_yaw(pose)).map(|(_, a)| p3(a))
    }

    /// The yaw of the rover frame whose axle makes `pose.yaw` the heading of the **rolling direction** (the
    /// rover's x axis in the tangent plane, as the flight software's `RoverState::heading`). The frame keeps its
    /// x axis horizontal and rolls the axle about it ([`Self::rotation`]): on level ground the two yaws are equal,
    /// on a slope they differ unless the rover faces along the fall line or the contour. The rolling direction
    /// `f` with horizontal heading `yaw` in the ground's tangent plane (normal `n`, from the terrain heights
    /// [`NORMAL_BASE_M`] around the axle) is `(cos yaw, sin yaw, -(n_x cos yaw + n_y sin yaw) / n_z)`; the axle
    /// is `n x f`, and the frame's yaw is the heading that puts its horizontal `across` along the axle's horizontal
    /// part. Before this conversion the judge set a rover 10 degrees off the fall line of the ledge's 55-degree
    /// face down with its axle 11 degrees from the planner's (`doc/physics_judge.md`, 2026-12-04). Where the
    /// ground cannot be sampled, the heading itself.
    pub fn frame_yaw(&self, pose: GroundPose) -> f64 {
        let Some(n) = self.ground_normal(pose.x, pose.y) else { return pose.yaw };
        let (c, s) = (pose.yaw.cos(), pose.yaw.sin());
        let f = Vector::new(c, s, -(n.x * c + n.y * s) / n.z);
        let a = n.cross(f);
        if a.x.hypot(a.y) < 1e-9 {
            return pose.yaw;
        }
        (-a.x).atan2(a.y)
    }

    /// The heading (as [`GroundPose::yaw`]) whose frame ([`Self::frame_yaw`]) lays the axle's horizontal part
    /// along `axle` (a world direction; only its horizontal part counts) at `(x, y)`: a pose handed over by its
    /// axle, so the judge sets the rover in the same vertical plane as whoever chose the pose. Where the ground
    /// is not one plane under the rover (straddling a lip), the rolling heading of two placements can differ by
    /// tens of degrees for the same axle, so a heading alone does not name the same pose. Bisection of the
    /// wrapped difference within 90 degrees either side of the axle's own normal; `None` if `axle` is vertical.
    pub fn heading_for_axle(&self, x: f64, y: f64, axle: P3) -> Option<f64> {
        if axle[0].hypot(axle[1]) < 1e-9 {
            return None;
        }
        let target = (-axle[0]).atan2(axle[1]);
        let wrap = |a: f64| (a + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU) - core::f64::consts::PI;
        let miss = |h: f64| wrap(self.frame_yaw(GroundPose { x, y, yaw: h }) - target);
        let half = core::f64::consts::FRAC_PI_2;
        let (mut lo, mut hi) = (target - half, target + half);
        if miss(lo) > 0.0 || miss(hi) < 0.0 {
            return Some(target);
        }
        for _ in 0..HEADING_BISECTIONS {
            let m = 0.5 * (lo + hi);
            if miss(m) <= 0.0 {
                lo = m;
            } else {
                hi = m;
            }
        }
        Some(wrap(0.5 * (lo + hi)))
    }

    /// The ground's upward normal under `(x, y)`: central differences of the terrain heights [`NORMAL_BASE_M`]
    /// away along x and y; `None` where one of them has no ground.
    fn ground_normal(&self, x: f64, y: f64) -> Option<Vector> {
        let h = NORMAL_BASE_M;
        let z = |dx: f64, dy: f64| self.terrain.top_at(x + dx, y + dy, self.z_lo, self.z_hi);
        let (xp, xm, yp, ym) = (z(h, 0.0)?, z(-h, 0.0)?, z(0.0, h)?, z(0.0, -h)?);
        Some(Vector::new(-(xp - xm) / (2.0 * h), -(yp - ym) / (2.0 * h), 1.0).normalize())
    }

    /// The heading of the rolling direction of a rover with axle direction `axle_dir` at `at` (the inverse of
    /// [`Self::frame_yaw`]): `axle x n`'s horizontal heading, `n` the ground normal there.
    fn rolling_heading(&self, at: Vector, axle_dir: Vector) -> Option<f64> {
        let f = axle_dir.cross(self.ground_normal(at.x, at.y)?);
        (f.x.hypot(f.y) > 1e-9).then(|| f.y.atan2(f.x))
    }

    /// The wheels set down at `pose` in the frame of yaw `frame_yaw` (see the module docs): the rover's rotation
    /// and axle centre.
    fn place_wheels(&self, pose: GroundPose, frame_yaw: f64) -> Option<(Rotation, Vector)> {
        let (r, ht) = (self.r(), self.half_track());
        let wheel = self.wheel_shape();
        let (c, s) = (frame_yaw.cos(), frame_yaw.sin());
        let across = [-s, c, 0.0];
        let ground = |k: f64| self.terrain.top_at(pose.x + k * ht * across[0], pose.y + k * ht * across[1], self.z_lo, self.z_hi);
        let (gl, gr) = (ground(1.0)?, ground(-1.0)?);
        // Each round: both wheels' cylinders cast straight down at the current roll give the heights their
        // centres touch at; the axle is re-rolled through those two points.
        let mut roll = ((gl - gr) / (2.0 * ht)).clamp(-0.99, 0.99).asin();
        let z_start = gl.max(gr) + r + 1.0;
        let touch = |roll: f64| -> Option<(Rotation, Vector, f64, f64)> {
            let rot = Self::rotation(frame_yaw, roll);
            let ay = rot * Vector::Y;
            let centre = Vector::new(pose.x, pose.y, z_start);
            let drop = |k: f64| {
                let p = Pose::from_parts(centre + ay * (k * ht), rot);
                self.terrain.cast_shape(&p, wheel.as_ref(), [0.0, 0.0, -1.0], z_start - self.z_lo)
            };
            Some((rot, ay, drop(1.0)?, drop(-1.0)?))
        };
        for _ in 0..PLACE_ROUNDS {
            let (_, ay, dl, dr) = touch(roll)?;
            let (hl, hr) = (z_start + ht * ay.z - dl, z_start - ht * ay.z - dr);
            roll = ((hl - hr) / (2.0 * ht)).clamp(-0.99, 0.99).asin();
        }
        let (mut rot, _, mut dl, mut dr) = touch(roll)?;
        if (dl - dr).abs() > PLACE_ROLL_TOLERANCE_M {
            // The rounds did not bring both wheels down (a wheel over an edge: the ground under its centre is far
            // below where its rim rests). Lower the rover level and pivot it about the wheel that touches first
            // until the other touches: the first root of `dl - dr` from roll 0, which grows with the roll.
            let gap = |roll: f64| touch(roll).map(|(_, _, dl, dr)| dl - dr);
            let g0 = gap(0.0)?;
            let dir = if g0 > 0.0 { -1.0 } else { 1.0 };
            let step = PLACE_PIVOT_STEP_DEG.to_radians();
            let (mut a, mut ga) = (0.0, g0);
            let mut b = None;
            for k in 1..=PLACE_PIVOT_STEPS {
                let r = dir * k as f64 * step;
                let gr = gap(r)?;
                if (gr > 0.0) != (ga > 0.0) {
                    b = Some(r);
                    break;
                }
                (a, ga) = (r, gr);
            }
            let mut b = b?;
            for _ in 0..PLACE_PIVOT_BISECTIONS {
                let m = 0.5 * (a + b);
                let gm = gap(m)?;
                if (gm > 0.0) == (ga > 0.0) {
                    (a, ga) = (m, gm);
                } else {
                    b = m;
                }
            }
            (rot, _, dl, dr) = touch(0.5 * (a + b))?;
        }
        let axle = Vector::new(pose.x, pose.y, z_start - dl.min(dr) + PLACE_GAP_M);
        let body_shape = Cylinder::new(ht - 0.5 * WHEEL_WIDTH_M - 0.01, f64::from(self.rover.body_radius_m));
        if self.terrain.intersects(&Pose::from_parts(axle, rot), &body_shape) {
            return None;
        }
        Some((rot, axle))
    }

    /// A fresh rapier world with the terrain and the rover at `pl`, brakes on, rope to `tether`.
    fn build(&self, pl: &Placement, tether: &TetherSpec) -> (PhysicsWorld, RoverBodies) {
        let yaw = pl.frame_yaw;
        let mut w = PhysicsWorld::new();
        w.gravity = Vector::new(0.0, 0.0, -f64::from(self.rover.gravity_mps2));
        w.integration_parameters.dt = 1.0 / STEP_HZ;
        for (pose, shape) in &self.terrain.parts {
            w.insert_collider(ColliderBuilder::new(shape.clone()).position(*pose).friction(1.0).build(), None);
        }
        let ay = v3(pl.axle_dir);
        let roll = ay.z.clamp(-1.0, 1.0).asin();
        let rot = Self::rotation(yaw, roll);
        let axle = v3(pl.axle);
        let p = &self.rover;
        let chassis = w.insert_body(RigidBodyBuilder::dynamic().pose(Pose::from_parts(axle, rot)).can_sleep(false).build());
        let ht = self.half_track();
        let rule = CoefficientCombineRule::Multiply;
        let body_mass = f64::from(p.body_mass_kg) - 2.0 * WHEEL_MASS_KG;
        let body = ColliderBuilder::cylinder(ht - 0.5 * WHEEL_WIDTH_M - 0.01, f64::from(p.body_radius_m))
            .mass(body_mass.max(1.0))
            .friction(f64::from(p.boom_mu))
            .friction_combine_rule(rule);
        w.insert_collider(body.build(), Some(chassis));
        let l = f64::from(p.boom_length_m);
        let tip_local = Vector::new(l * pl.boom_angle.cos(), 0.0, l * pl.boom_angle.sin());
        let boom = ColliderBuilder::capsule_from_endpoints(Vector::ZERO, tip_local, BOOM_RADIUS_M)
            .mass(f64::from(p.boom_mass_kg))
            .friction(f64::from(p.boom_mu))
            .friction_combine_rule(rule);
        w.insert_collider(boom.build(), Some(chassis));
        let mut wheels = [chassis; 2];
        let mut joints = Vec::with_capacity(2);
        for (k, side) in [1.0, -1.0].into_iter().enumerate() {
            let at = axle + rot * Vector::new(0.0, side * ht, 0.0);
            let wb = w.insert_body(RigidBodyBuilder::dynamic().pose(Pose::from_parts(at, rot)).can_sleep(false).build());
            let col = ColliderBuilder::new(self.wheel_shape()).mass(WHEEL_MASS_KG).friction(f64::from(p.wheel_mu)).friction_combine_rule(rule);
            w.insert_collider(col.build(), Some(wb));
            let joint = RevoluteJointBuilder::new(Vector::Y)
                .local_anchor1(Vector::new(0.0, side * ht, 0.0))
                .local_anchor2(Vector::ZERO)
                .limits([0.0, 0.0])
                .contacts_enabled(false);
            joints.push(w.insert_impulse_joint(chassis, wb, joint));
            wheels[k] = wb;
        }
        let tip = v3(pl.tip);
        let anchor = v3(tether.anchor);
        let len = tether.free_length_m.unwrap_or_else(|| (anchor - tip).length());
        let rope = (len > 1e-6).then(|| {
            let fixed = w.insert_body(RigidBodyBuilder::fixed().translation(anchor).build());
            w.insert_impulse_joint(fixed, chassis, RopeJointBuilder::new(len).local_anchor1(Vector::ZERO).local_anchor2(tip_local))
        });
        let wheel_joints = [joints[0], joints[1]];
        (w, RoverBodies { chassis, wheels, wheel_joints, rope })
    }

    /// The tether's last anchor when it ends at the boom tip rather than at the axle: the inline boom is aimed at
    /// `first` (the last anchor of a tether to the axle, or the previous pose's), `anchor_for_tip` gives the true
    /// tether's last anchor for a tether ending at that tip, and the boom is re-aimed, at most [`AIM_ROUNDS`] times,
    /// until the anchor moves less than [`AIM_TOLERANCE_M`]. Within a boom length of an edge this matters: just
    /// over a lip the boom reaches back past it, and the tether runs from the tip to the root, not down to the lip.
    /// `Ok(None)`: the rover cannot be placed at `pose`.
    pub fn aim_tether<E>(
        &self,
        pose: GroundPose,
        first: P3,
        mut anchor_for_tip: impl FnMut(P3) -> Result<P3, E>,
    ) -> Result<Option<P3>, E> {
        let mut anchor = first;
        for _ in 0..AIM_ROUNDS {
            let Some(pl) = self.place(pose, anchor, BoomSetting::Inline) else { return Ok(None) };
            let next = anchor_for_tip(pl.tip)?;
            let moved = firmware::geom::p3::dist(next, anchor);
            anchor = next;
            if moved < AIM_TOLERANCE_M {
                break;
            }
        }
        Ok(Some(anchor))
    }

    /// The hold test (see the module docs): the boom settings of [`BOOM_SETTINGS`] in turn, the first that holds
    /// is the verdict; if none holds, the inline setting's verdict (or the first that could be placed).
    pub fn hold(&self, pose: GroundPose, tether: &TetherSpec) -> HoldVerdict {
        let mut first: Option<HoldVerdict> = None;
        for boom in BOOM_SETTINGS {
            let v = self.hold_with(pose, tether, boom);
            if v.holds() {
                return v;
            }
            if first.is_none_or(|f| f.outcome == HoldOutcome::Blocked) {
                first = Some(v);
            }
        }
        first.unwrap_or(HoldVerdict { outcome: HoldOutcome::Blocked, placement: None, slide_m: 0.0, tilt_deg: 0.0, end_speed_mps: 0.0 })
    }

    /// The hold test with one boom setting.
    pub fn hold_with(&self, pose: GroundPose, tether: &TetherSpec, boom: BoomSetting) -> HoldVerdict {
        let Some(pl) = self.place(pose, tether.anchor, boom) else {
            return HoldVerdict { outcome: HoldOutcome::Blocked, placement: None, slide_m: 0.0, tilt_deg: 0.0, end_speed_mps: 0.0 };
        };
        let (mut w, rb) = self.build(&pl, tether);
        let (p0, a0) = (v3(pl.axle), v3(pl.axle_dir));
        let (mut slide, mut tilt) = (0.0f64, 0.0f64);
        let steps = (HOLD_SECONDS * STEP_HZ).round() as usize;
        for _ in 0..steps {
            w.step();
            let c = &w.bodies[rb.chassis];
            slide = slide.max((c.translation() - p0).length());
            tilt = tilt.max(angle_between(*c.rotation() * Vector::Y, a0));
            // Already far beyond the slide threshold: the rest of the run changes nothing.
            if slide > 4.0 * HOLD_SLIDE_M {
                break;
            }
        }
        let speed = w.bodies[rb.chassis].linvel().length();
        let holds = slide < HOLD_SLIDE_M && tilt.to_degrees() < HOLD_TILT_DEG && speed < HOLD_END_SPEED_MPS;
        HoldVerdict {
            outcome: if holds { HoldOutcome::Holds } else { HoldOutcome::Falls },
            placement: Some(pl),
            slide_m: slide,
            tilt_deg: tilt.to_degrees(),
            end_speed_mps: speed,
        }
    }

    /// The drive test (see the module docs).
    pub fn drive(&self, start: GroundPose, tether: &TetherSpec, command: DriveCommand) -> DriveReport {
        let none = DriveReport { placed: false, fell: false, completed: false, end_axle: [0.0; 3], end_yaw: start.yaw, max_tilt_deg: 0.0, seconds: 0.0 };
        let boom = BOOM_SETTINGS.into_iter().find(|b| self.hold_with(start, tether, *b).holds()).unwrap_or(BoomSetting::Inline);
        let Some(pl) = self.place(start, tether.anchor, boom) else { return none };
        let (mut w, rb) = self.build(&pl, tether);
        let r = self.r();
        // Target wheel rates (left, right) and the odometry goal (wheel arc length, metres).
        let (rates, goal, budget) = match command {
            DriveCommand::Straight { distance_m, speed_mps } => {
                let v = speed_mps.abs().max(1e-3) * distance_m.signum();
                ([v / r, v / r], distance_m.abs(), distance_m.abs())
            }
            DriveCommand::Turn { angle_rad, rate_radps } => {
                let v = rate_radps.abs().max(1e-3) * self.half_track() * angle_rad.signum();
                // Counter-clockwise: the right wheel (-y) forward, the left wheel back.
                ([-v / r, v / r], angle_rad.abs() * self.half_track(), angle_rad.abs())
            }
        };
        for (k, j) in rb.wheel_joints.iter().enumerate() {
            if let Some(joint) = w.impulse_joints.get_mut(*j, true) {
                // The joint's free axis is its local x (the axle). Velocity-controlled, torque cap far above what
                // 50 kg on a slope needs.
                joint.data.limit_axes.remove(JointAxesMask::ANG_X);
                joint.data.set_motor_velocity(JointAxis::AngX, rates[k], 1e4);
                joint.data.set_motor_max_force(JointAxis::AngX, 1e4);
            }
        }
        let a0 = v3(pl.axle_dir);
        let tip_local = {
            let l = f64::from(self.rover.boom_length_m);
            Vector::new(l * pl.boom_angle.cos(), 0.0, l * pl.boom_angle.sin())
        };
        let anchor = v3(tether.anchor);
        let mut rope_len = tether.free_length_m.unwrap_or_else(|| (anchor - v3(pl.tip)).length());
        let max_steps = ((budget * DRIVE_MAX_SECONDS + 1.0) * STEP_HZ).ceil() as usize;
        let (mut odo, mut tilt, mut t) = (0.0f64, 0.0f64, 0.0f64);
        let mut completed = false;
        let wheel_rate = |w: &PhysicsWorld| {
            let c = &w.bodies[rb.chassis];
            let ax = *c.rotation() * Vector::Y;
            let rel: [f64; 2] = [0, 1].map(|k| (w.bodies[rb.wheels[k]].angvel() - c.angvel()).dot(ax));
            rel
        };
        for _ in 0..max_steps {
            w.step();
            t += 1.0 / STEP_HZ;
            let rel = wheel_rate(&w);
            odo += 0.5 * (rel[0].abs() + rel[1].abs()) * r / STEP_HZ;
            let c = &w.bodies[rb.chassis];
            tilt = tilt.max(tilt_out_of_plane(*c.rotation() * Vector::Y, a0, &command));
            // Winch: taut, paying out no faster than the wheels roll.
            let tip = c.translation() + *c.rotation() * tip_local;
            let d = (tip - anchor).length();
            let pay = 0.5 * (rel[0].abs() + rel[1].abs()) * r / STEP_HZ;
            rope_len = d.min(rope_len + pay).max(1e-3);
            if let Some(j) = rb.rope.and_then(|h| w.impulse_joints.get_mut(h, false)) {
                j.data.set_limits(JointAxis::LinX, [0.0, rope_len]);
            }
            if odo >= goal {
                completed = true;
                break;
            }
        }
        // Brakes: the motors off, each wheel locked where it is (its current angle relative to the chassis).
        for (k, j) in rb.wheel_joints.iter().enumerate() {
            let (c, wr) = (*w.bodies[rb.chassis].rotation(), *w.bodies[rb.wheels[k]].rotation());
            if let Some(joint) = w.impulse_joints.get_mut(*j, true) {
                let rel = RevoluteJoint { data: joint.data }.angle(&c, &wr);
                joint.data.set_motor_max_force(JointAxis::AngX, 0.0);
                joint.data.set_limits(JointAxis::AngX, [rel, rel]);
            }
        }
        let settle = (DRIVE_SETTLE_SECONDS * STEP_HZ).round() as usize;
        for _ in 0..settle {
            w.step();
            t += 1.0 / STEP_HZ;
            let c = &w.bodies[rb.chassis];
            tilt = tilt.max(tilt_out_of_plane(*c.rotation() * Vector::Y, a0, &command));
        }
        let c = &w.bodies[rb.chassis];
        let fwd = *c.rotation() * Vector::X;
        let end_yaw = self.rolling_heading(c.translation(), *c.rotation() * Vector::Y).unwrap_or_else(|| fwd.y.atan2(fwd.x));
        let speed = c.linvel().length();
        DriveReport {
            placed: true,
            fell: tilt.to_degrees() > FALL_TILT_DEG || speed > HOLD_END_SPEED_MPS,
            completed,
            end_axle: p3(c.translation()),
            end_yaw,
            max_tilt_deg: tilt.to_degrees(),
            seconds: t,
        }
    }
}

/// How far the axle `a` has turned from `a0`: the full angle for a straight drive; for a turn in place only the
/// part out of the horizontal (its elevation change), since turning the axle about the vertical is the command.
fn tilt_out_of_plane(a: Vector, a0: Vector, command: &DriveCommand) -> f64 {
    match command {
        DriveCommand::Straight { .. } => angle_between(a, a0),
        DriveCommand::Turn { .. } => (a.normalize().z.clamp(-1.0, 1.0).asin() - a0.normalize().z.clamp(-1.0, 1.0).asin()).abs(),
    }
}

/// The free tether length from `anchor` to the boom tip of `pl` when taut.
pub fn taut_length(pl: &Placement, anchor: P3) -> f64 {
    norm(sub(anchor, pl.tip))
}

#[cfg(test)]
mod tests;
