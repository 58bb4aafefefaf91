//! Parameterized texture codec (placeholder until the codec issue lands).
