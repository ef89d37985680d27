//! Studies built on the impact engine: energy accounting, spectra, sweeps, optimisation.

pub mod blows;
pub mod compare;
pub mod energy;
pub mod esd;
pub mod impacts;
pub mod montecarlo;
pub mod network;
pub mod network_blows;
pub mod network_study;
pub mod octave;
pub mod optimize;
pub mod placement;
pub mod production;
pub mod quadrature;
pub mod return_map;
pub mod sketch;
pub mod spectrum;
pub mod steady;
pub mod study;
pub mod sweep;
pub mod table;

pub use energy::{simulate, EnergyTerms, History, Run, Summary};
