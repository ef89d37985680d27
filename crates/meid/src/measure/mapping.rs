//! Which measured channel is which simulated one.
