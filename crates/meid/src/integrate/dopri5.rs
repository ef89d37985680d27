//! Dormand-Prince 5(4) (placeholder until written).
use super::{Observer, Options, Solution};
use crate::impact::ImpactSystem;
use crate::{Error, Result};

/// Runs Dormand-Prince 5(4).
pub fn solve(_sys: &ImpactSystem, _opts: &Options, _obs: &mut dyn Observer) -> Result<Solution> {
    Err(Error::numerical("dopri5", "not yet available"))
}
