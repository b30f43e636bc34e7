//! Idempotent requests (protocol v5, issue 24 item 1): a resent request the executive already acted on is answered
//! `Ack` and not acted on again.
//!
//! The host resends a state-changing frame that got no answer, under a new sequence number (so the v4 duplicate
//! check, which catches copies made by the link, lets it through). When it was the `Ack` that the downlink lost, the
//! flight software already acted on the first copy. A `Configure` or a `GoalRequest` applied twice would reset the
//! navigator or replace (and restart) the goal, so the executive remembers the identity of the last one of each it
//! accepted: its kind and the CRC-32 of its body (a resend is byte for byte the same body). The same request again
//! is a repeat: `Ack`, nothing else, counted (`Telemetry.requests_repeated`). A request that was refused changed
//! nothing and is not remembered, so its resend is handled afresh.
//!
//! The other state-changing requests are idempotent by their own checks: a `MotionReport` already accepted is
//! `Nack(UnknownCommand)`, a `GoalCancel` already done `Nack(UnknownGoal)`, a scan chunk already received
//! `Nack(DuplicateChunk)`, a `Shutdown` in Safe `Nack(NotAllowedInMode)`; none of them acts twice.
//!
//! Limit: one remembered request per kind. To apply the same `Configure` or goal again, the host changes it (a new
//! goal id); a resend overtaken by a newer request of its kind would be taken as new, so the host never resends a
//! superseded goal (`host-sim` `session`).

use crate::protocol::{frame::CRC, Message};

/// The identity of a request that must not act twice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum RequestKey {
    /// A `Configure`: the CRC-32 of its body.
    Configure(u32),
    /// A `GoalRequest`: the CRC-32 of its body.
    Goal(u32),
}

impl RequestKey {
    fn of(msg: &Message, body: &[u8]) -> Option<Self> {
        match msg {
            Message::Configure(_) => Some(RequestKey::Configure(CRC.checksum(body))),
            Message::GoalRequest(_) => Some(RequestKey::Goal(CRC.checksum(body))),
            _ => None,
        }
    }
}

/// The last accepted request of each kind (module docs).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct LastRequests {
    configure: Option<RequestKey>,
    goal: Option<RequestKey>,
}

impl LastRequests {
    fn slot(&mut self, key: RequestKey) -> &mut Option<RequestKey> {
        match key {
            RequestKey::Configure(_) => &mut self.configure,
            RequestKey::Goal(_) => &mut self.goal,
        }
    }

    /// Whether `msg` (with body `body`) repeats the last accepted request of its kind.
    pub(super) fn is_repeat(&mut self, msg: &Message, body: &[u8]) -> bool {
        RequestKey::of(msg, body).is_some_and(|k| *self.slot(k) == Some(k))
    }

    /// Notes that `msg` was accepted.
    pub(super) fn accepted(&mut self, msg: &Message, body: &[u8]) {
        if let Some(k) = RequestKey::of(msg, body) {
            *self.slot(k) = Some(k);
        }
    }
}
