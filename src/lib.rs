//! saddle
