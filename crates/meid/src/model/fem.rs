//! Finite-element structures in model files (`[structure.fem]`): being built.

use serde::{Deserialize, Serialize};

use super::Source;
use crate::modal::ModalModel;
use crate::Result;

/// `[structure.fem]`: the parametric machine or a Gmsh mesh, reduced to selected modes.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct FemSpec {}

/// Builds, solves and reduces the finite-element structure.
pub fn modal_model(_spec: &FemSpec, src: &Source) -> Result<ModalModel> {
    Err(src.error(
        "structure.fem",
        "finite-element structures are not available yet",
    ))
}
