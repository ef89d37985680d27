//! Dense generalised symmetric eigen-solver (to be written).
