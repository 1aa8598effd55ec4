//! Voxel data for niebla.
