//! Sparse shift-invert block Lanczos (to be written).
