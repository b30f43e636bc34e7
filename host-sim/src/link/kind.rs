//! [`LinkKind`]: the choice of flight software a run talks to (`--link inproc|qemu` of `run`, `record`, `replay`).

/// Which flight software a run talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "sim", derive(clap::ValueEnum))]
pub enum LinkKind {
    /// The executive linked into the host, stepped on a simulated clock (fast; the default).
    #[default]
    Inproc,
    /// The cross-compiled board binary in QEMU (mps2-an500, Cortex-M7) over an emulated UART, stepped in
    /// lockstep on the same simulated clock (byte-identical output to `inproc`).
    Qemu,
}
