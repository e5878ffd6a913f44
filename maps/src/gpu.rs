//! The wgpu depth backend (being written).
