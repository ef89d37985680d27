//! Finite-element model of the machine structure (paper section 3): four- and three-node shell elements for
//! the bed and the floating base, 3-D frame elements for the columns, coil springs, point masses
//! and rigid links; sparse assembly; the parametric machine of the paper's Fig. 1; a Gmsh reader.
//!
//! | file | content |
//! |---|---|
//! | [`frame`] | 12-DOF Euler-Bernoulli frame, cross-sections |
//! | [`shell`] | 24-DOF flat shell: Q4 membrane + MITC4 bending + drilling penalty |
//! | [`tri3`] | 18-DOF flat shell: CST membrane + DKT bending + drilling penalty |
//! | [`discrete`] | springs, dashpots, point masses, rigid links |
//! | [`mesh`] | nodes, elements, supports, named points, validation |
//! | [`assembly`] | DOF numbering with rigid-link elimination, sparse/dense K, M, C, floor force |
//! | [`modes`] | modal model (paper Eq. 9) and mode tables from the dense modes |
//! | [`machine`] | the parametric forging machine (paper Fig. 1), a generator of the general model |
//! | [`gmsh`] | Gmsh `.msh` 4.1 ASCII meshes: quadrangles, triangles, lines |
//!
//! All elements are hand-written: no Rust crate offers shell or frame elements; the linear algebra
//! is faer's.
//!
//! Units are SI: m, kg, s, N, Pa. Each node carries six DOFs `[ux, uy, uz, rx, ry, rz]` in global axes.

// Element matrices are small fixed-size loops over nodes and DOFs: index loops read like the
// formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod compress;
pub mod discrete;
pub mod frame;
pub(crate) mod geom;
pub mod gmsh;
pub mod machine;
pub mod material;
pub mod mesh;
pub mod modes;
pub mod shell;
pub mod tri3;

pub use assembly::{DofMap, FeModel, StiffSpring, DOF_NAMES};
pub use discrete::{Dashpot, PointMass, RigidLink, Spring};
pub use frame::{FrameElement, Section};
pub use machine::{GeneratedMachine, Machine, MachineSpec, Support};
pub use material::Material;
pub use mesh::{Dof, Mesh, MeshPart};
pub use modes::ModeTable;
pub use shell::ShellElement;
pub use tri3::TriShellElement;
