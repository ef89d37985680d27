//! (module under construction)
pub mod matrix_market;
