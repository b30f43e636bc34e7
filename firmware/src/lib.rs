//! # firmware — flight software for tethered extreme-terrain rovers
//!
//! A `no_std`, heap-free planning core plus the flight executive, generic over the rover-computer HAL (`hal`).
//! The same code runs in-process inside the host simulator and cross-compiled on the flight computer
//! (`firmware/boards/*`).
//!
//! ## Layers (each uses only the ones above it; the modules of one line form one layer)
//! - [`geom`]: vectors, transforms, planes, polygons over `nalgebra` (no_std) and `libm`.
//! - [`config`]: every capacity (arena size) and every budget (iterations, solver steps) in one place.
//! - [`protocol`]: wire format between simulator / ground and flight software (postcard bodies, COBS, CRC).
//! - [`map`]: onboard terrain map (TSDF -> ESDF in a fixed pool of voxel blocks) — Paton et al. IV.
//! - [`rover`], [`tether`], [`stability`]: tether-aware traversability — Paton et al. IV-A, IV-B, IV-C.
//! - [`plan`]: planners: ABIT* (Paton et al. V), homotopy planning on tether-demand planes (Abad-Manterola et
//!   al.; Tanner et al.), tethered climbing teams (Morad et al.), and the flight RNG ([`plan::SplitMix64`]).
//! - [`exec`]: the flight executive: mode machine, frame dispatch, per-cycle budgets, telemetry, and the
//!   [`exec::Autonomy`] hooks where the map and the planners plug in.
//! - [`nav`]: the executive's autonomy: builds the onboard map from the link's scans and plans goal requests on
//!   it (tethered ABIT*, Paton et al. IV-V).
//!
//! Flight code only: the fixed benchmark workloads (on-target instruction counts and their host twins) and the
//! planners' test problems are the `workloads` crate (`firmware/workloads/`), which depends on this one.
//!
//! ## Rules of the core
//! - **No heap, no panic.** Containers are `heapless` or fixed arrays; a full container is a typed outcome.
//!   Large arenas are owned by the caller (board crate or host) and lent to the core.
//! - **Every loop is bounded** by a named budget from [`config`]. Running out of budget is an outcome that keeps the
//!   work done so far.
//! - **Deterministic.** Randomness comes from a seeded `rand_core` generator passed in; transcendental functions
//!   go through `libm`; no hash-ordered iteration; time is passed in. Same inputs, same bytes out, on x86_64 and
//!   on the ARM flight computer.
//!
//! Numbers: the 3D map and rover use `f32` ([`geom::Real`]); solvers that need the headroom (QP, L-values) use
//! `f64` internally. Both are IEEE-exact on the Cortex-M7 (f64 in its double-precision FPU: the flight build sets
//! `target-cpu=cortex-m7`, `.cargo/config.toml`).
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

#[cfg(test)]
extern crate std;

pub mod config;
pub mod exec;
pub mod geom;
pub mod map;
pub mod nav;
pub mod plan;
pub mod protocol;
pub mod rover;
pub mod stability;
pub mod tether;
