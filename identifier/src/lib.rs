//! Hyperelastic identification of rubber-like materials (paper section 4).
//!
//! - [`law`]: the invariant-based law W(I1, I2) with f(I1), g(I2) (eqs 18-25), Smactane™ default.

pub mod law;
