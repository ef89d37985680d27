//! (module under construction)
pub mod optimize;
pub mod spectrum;
