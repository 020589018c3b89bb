//! Placeholder: the penalty solver (being written).

/// `type = "penalty"` (being written).
#[derive(Clone, Debug, Default)]
pub struct Penalty;
