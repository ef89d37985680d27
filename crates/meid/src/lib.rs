//! # meid — momentum-exchange impact dampers for impact machines
//!
//! The library behind the `meid` command. It follows the data flow of a study:
//!
//! | stage | module | job |
//! |---|---|---|
//! | input | [`model`] | TOML model files, `--set` overrides, validation with file/line/column errors |
//! | structure | [`structure`] | finite elements (shell, frame, springs, masses), mesh, sparse assembly |
//! | modes | [`modal`] | generalised symmetric eigen-solvers, the reduced [`modal::ModalModel`] (paper Eq. 9) |
//! | impact | [`impact`] | slider, bed, damper, unilateral contacts: the piecewise-linear system (Eqs. 1-8) |
//! | time | [`integrate`] | exact event-driven propagation; Dormand-Prince 5(4) with event location |
//! | studies | [`analysis`] | energies (Eqs. 10-24), spectra, sweeps, optimisation, comparisons |
//! | output | [`io`], [`plot`] | CSV/JSON/VTK files written atomically, PNG/SVG pictures |
//! | reports | [`report`] | self-contained HTML pages (figures with captions, tables) |
//! | limits | [`limits`] | memory estimated and checked before a run allocates |
//!
//! Units are SI throughout (m, kg, s, N, rad/s unless a name says Hz).
//! The library never prints; progress is reported through callbacks.

// Index loops over several arrays at once are the clearest form of numerical kernels.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod error;
pub mod impact;
pub mod input;
pub mod integrate;
pub mod io;
pub mod limits;
pub mod measure;
pub mod modal;
pub mod model;
pub mod plot;
pub mod report;
pub mod rng;
pub mod structure;

pub use error::{num, Error, Result};
