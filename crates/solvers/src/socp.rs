//! Placeholder: the SOCP solver (being written).

/// `type = "socp"` (being written).
#[derive(Clone, Debug, Default)]
pub struct Socp;
