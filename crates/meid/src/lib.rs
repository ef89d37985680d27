//! # meid — momentum-exchange impact dampers for impact machines
//!
//! The library behind the `meid` command. It follows the data flow of a study:
//!
//! | stage | module | job |
//! |---|---|---|
//! | input | [`model`] | TOML model files, `--set` overrides, validation with file/line/column errors |
//! | structure | [`structure`] | finite elements (shell, frame, springs, masses), mesh, sparse assembly |
//! | modes | [`modal`] | generalised symmetric eigen-solvers, the reduced [`modal::ModalModel`] (paper Eq. 9) |
//! | impact | [`impact`] | slider, bed, damper, unilateral contacts: the piecewise-linear system (Eqs. 1-8); any number of impactors, dampers and contacts ([`impact::network`]) |
//! | time | [`integrate`] | exact event-driven propagation (the paper's system, and a general machine: [`integrate::network`]); Dormand-Prince 5(4) with event location |
//! | studies | [`analysis`] | energies (Eqs. 10-24), spectra, sweeps, optimisation, comparisons |
//! | surroundings | [`foundation`] | the block on the soil, ground vibration at receivers, DIN 4150 / ISO 2631 / IS 2974 checks |
//! | measured data | [`record`], [`measure`] | records in SI; blows, spectra, FRFs, validation, calibration |
//! | modal testing | [`identify`] | modes from FRFs: LSCF poles, stabilisation diagram, LSFD shapes |
//! | output | [`io`], [`plot`] | file formats (CSV/JSON/VTK/UFF/Parquet, written atomically), PNG/SVG pictures |
//! | reports | [`report`] | self-contained HTML pages (figures with captions, tables) |
//! | limits | [`limits`] | memory estimated and checked before a run allocates |
//!
//! ## Layers
//!
//! Each stage imports only the stages on the lines below its own, so no module imports a
//! module that imports it back (the `meid` command and the Python package sit on top):
//!
//! | layer | modules | may import |
//! |---|---|---|
//! | 9 reports | [`report`] | everything below |
//! | 8 measured data | [`measure`] | `analysis`, `model`, `io`, `record`, `plot`, `impact`, `identify` and the base |
//! | 8 surroundings | [`foundation`] | `analysis`, `model`, `integrate`, `modal` and the base |
//! | 7 studies | [`analysis`] | `model`, `integrate`, `impact`, `io`, `modal`, `plot` and the base |
//! | 6 model files | [`model`] | `integrate`, `impact`, `io` (its readers), `structure`, `modal` and the base |
//! | 5 time | [`integrate`] | `impact`, `modal` and the base |
//! | 4 impact system | [`impact`] | `modal` and the base |
//! | 4 formats | [`io`] | `structure`, `modal`, `record` and the base: formats only, no study or model type |
//! | 3 structure | [`structure`] | `modal` and the base |
//! | 2 modes, pictures, records, identification | [`modal`], [`plot`], [`record`], [`identify`] | the base |
//! | 1 base | [`error`], [`input`], [`limits`], [`rng`] | one another, downwards (`input` → `limits` → `error`) |
//!
//! Two imports run up across the layers, each from one file and through data types alone:
//! [`structure::machine`], the generator of the paper's machine, emits the general model
//! ([`model::general::GeneralSpec`], with [`model::material`] and [`model::source::Source`]),
//! which [`model::fem`] calls it for; and [`model::spec`] holds the model file's
//! `[measurement]` section, [`measure::mapping::MeasurementSpec`]. Neither file is imported
//! back by what it imports.
//!
//! Units are SI throughout (m, kg, s, N, rad/s unless a name says Hz).
//! The library never prints; progress is reported through callbacks.

// Index loops over several arrays at once are the clearest form of numerical kernels.
#![allow(clippy::needless_range_loop)]

pub mod analysis;
pub mod error;
pub mod foundation;
pub mod identify;
pub mod impact;
pub mod input;
pub mod integrate;
pub mod io;
pub mod limits;
pub mod measure;
pub mod modal;
pub mod model;
pub mod plot;
pub mod record;
pub mod report;
pub mod rng;
pub mod structure;

pub use error::{num, Error, Result};
