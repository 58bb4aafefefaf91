//! The frame as an explicit list of passes, and the executor that runs it.

pub mod executor;
pub mod pass;
pub mod states;

pub use executor::{Executor, PassTiming};
pub use pass::{Access, Pass, Usage};
pub use states::ImageStates;
