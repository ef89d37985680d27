//! Simulation beside measurement.
