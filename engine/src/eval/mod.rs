//! `engine eval` (the speed/accuracy table): the traced reference of any
//! view, metrics over a reflector's pixels, the rows and views measured,
//! the table, its chart and pictures, and the driver; and the relighting
//! measurement (`engine relight`, and its rows in the table).

pub mod bars;
pub mod chart;
pub mod metrics;
pub mod noise;
pub mod path_score;
pub mod pictures;
pub mod plot;
pub mod reference;
pub mod relight;
mod row_scores;
pub mod rows;
pub mod run;
pub mod table;
pub mod views;

pub use run::{EvalOptions, eval, reflector_names};
