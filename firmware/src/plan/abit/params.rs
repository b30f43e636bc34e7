//! The planner's parameters ([`AbitParams`]) and their defaults (OMPL 1.5.2's ABIT*, plus `config::abit`).

use crate::config::abit as cfg;

use crate::plan::space::InvalidInput;

/// How the implicit RGG connects states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Connection {
    /// k-nearest (OMPL's default for BIT*/ABIT*).
    KNearest,
    /// r-disc.
    RDisc,
}

/// Planner parameters. See the module docs for the defaults and their sources.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbitParams {
    /// Samples per batch.
    pub samples_per_batch: u32,
    /// RGG rewire factor.
    pub rewire_factor: f64,
    /// k-nearest or r-disc.
    pub connection: Connection,
    /// Inflation of the first search of every batch.
    pub initial_inflation_factor: f64,
    /// Final search inflation is `1 + inflation_scaling_parameter / q`.
    pub inflation_scaling_parameter: f64,
    /// Truncation factor is `1 + truncation_scaling_parameter / q`.
    pub truncation_scaling_parameter: f64,
    /// Prune the graph before batches.
    pub pruning: bool,
    /// Prune only if at least this fraction of states can be pruned.
    pub prune_fraction: f64,
    /// Fraction of new samples that copy the nearest tree vertex's attachment (non-Markovian spaces only).
    pub attachment_copy_fraction: f64,
    /// Add a goal with undetermined attachment after each improvement (non-Markovian spaces only).
    pub fresh_goal_on_improvement: bool,
    /// When a vertex's outgoing edge reaches a tree vertex of an incompatible history, connect it to a twin of
    /// that state with undetermined history instead (up to `config::abit::MAX_HISTORY_TWINS` per state;
    /// non-Markovian spaces only). See the module docs.
    pub history_twins: bool,
    /// Report the vertex closest to the goal as an approximate solution when no exact one exists.
    pub track_approximate: bool,
    /// Sampling attempts per requested sample.
    pub sample_attempts_per_sample: u32,
    /// Uniform draws per informed sample when the objective has no direct informed sampler.
    pub informed_rejection_attempts: u32,
    /// BIT*'s edge-queue pruning as the paper states it (Gammell et al. 2020: after a vertex improves, the queued
    /// edges into it that can no longer improve it leave the queue), instead of OMPL's lazy discard at the front
    /// of the queue, which costs an iteration per edge. Same search, fewer iterations; off by default, because
    /// OMPL's iteration count (and so Paton et al.'s Table I) includes those discards. An experiment knob.
    pub drop_dead_edges: bool,
    /// Every vertex also queues its edges to the goals, whatever their distance (non-Markovian spaces only; see
    /// the module docs).
    pub goal_edges: bool,
    /// Queue an edge between two tree vertices that cannot improve the child when the space predicts that the
    /// motion would give the child another attachment; it connects a history twin (non-Markovian spaces with
    /// `history_twins` only; see the module docs).
    pub reveal_attachments: bool,
    /// Fraction of sample draws taken near where a known attachment would change
    /// ([`StateSpace::sample_catch_boundary`](crate::plan::space::StateSpace::sample_catch_boundary); non-Markovian
    /// spaces only; see the module docs).
    pub catch_sample_fraction: f64,
    /// Sample draws per `step` while a batch is drawn; 0 draws the whole batch in the iteration that starts it
    /// (OMPL). With a bound, a batch is drawn over several steps that are not iterations (counted in
    /// `Counters::sampling_steps`), so a caller that bounds its work per call (the on-board navigator, per
    /// executive step) can stop between them; the search is the same draw for draw.
    pub draws_per_step: u32,
    /// Before a batch while there is no solution, free unconnected samples (the oldest batch's first) until the
    /// node arena has room for `config::abit::ROOM_FOR_BATCHES` batches. Off, a search that connects few samples
    /// ends `ArenaFull` with nothing found once the arena is full of them. OMPL's arena is unbounded, so this acts
    /// only where OMPL's would have outgrown ours.
    pub evict_samples: bool,
}

impl AbitParams {
    /// OMPL 1.5.2's ABIT* defaults (plus the non-Markovian defaults of `config::abit`).
    pub const fn ompl_defaults() -> Self {
        Self {
            samples_per_batch: cfg::SAMPLES_PER_BATCH,
            rewire_factor: cfg::REWIRE_FACTOR,
            connection: Connection::KNearest,
            initial_inflation_factor: cfg::INITIAL_INFLATION_FACTOR,
            inflation_scaling_parameter: cfg::INFLATION_SCALING_PARAMETER,
            truncation_scaling_parameter: cfg::TRUNCATION_SCALING_PARAMETER,
            pruning: true,
            prune_fraction: cfg::PRUNE_FRACTION,
            attachment_copy_fraction: cfg::ATTACHMENT_COPY_FRACTION,
            fresh_goal_on_improvement: true,
            history_twins: true,
            track_approximate: false,
            sample_attempts_per_sample: cfg::SAMPLE_ATTEMPTS_PER_SAMPLE,
            informed_rejection_attempts: cfg::INFORMED_REJECTION_ATTEMPTS,
            drop_dead_edges: false,
            goal_edges: true,
            reveal_attachments: true,
            catch_sample_fraction: cfg::CATCH_SAMPLE_FRACTION,
            draws_per_step: 0,
            evict_samples: true,
        }
    }

    /// Checks every parameter (the planner's set-up runs the same check and reports `InvalidInput`): callers
    /// that take parameters from a user reject bad ones up front with the reason.
    pub fn validate(&self) -> Result<(), InvalidInput> {
        self.check()
    }

    pub(super) fn check(&self) -> Result<(), InvalidInput> {
        let p = InvalidInput::Parameter;
        if self.samples_per_batch == 0 {
            return Err(p("samples_per_batch must be at least 1"));
        }
        if !(self.rewire_factor > 0.0 && self.rewire_factor.is_finite()) {
            return Err(p("rewire_factor must be positive and finite"));
        }
        if !(self.initial_inflation_factor >= 1.0 && self.initial_inflation_factor.is_finite()) {
            return Err(p("initial_inflation_factor must be >= 1 and finite"));
        }
        if !(self.inflation_scaling_parameter >= 0.0 && self.inflation_scaling_parameter.is_finite()) {
            return Err(p("inflation_scaling_parameter must be >= 0 and finite"));
        }
        if !(self.truncation_scaling_parameter >= 0.0 && self.truncation_scaling_parameter.is_finite()) {
            return Err(p("truncation_scaling_parameter must be >= 0 and finite"));
        }
        if !(0.0..=1.0).contains(&self.prune_fraction) {
            return Err(p("prune_fraction must be in [0, 1]"));
        }
        if !(0.0..=1.0).contains(&self.attachment_copy_fraction) {
            return Err(p("attachment_copy_fraction must be in [0, 1]"));
        }
        if !(0.0..=1.0).contains(&self.catch_sample_fraction) {
            return Err(p("catch_sample_fraction must be in [0, 1]"));
        }
        if self.sample_attempts_per_sample == 0 || self.informed_rejection_attempts == 0 {
            return Err(p("sampling attempts must be at least 1"));
        }
        Ok(())
    }
}

impl Default for AbitParams {
    fn default() -> Self {
        Self::ompl_defaults()
    }
}
