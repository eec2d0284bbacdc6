//! Hyperelastic identification of rubber-like materials (not implemented yet).
