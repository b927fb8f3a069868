//! From mechanics to equations of motion: the shared derivation ([`mechanics`]), the
//! ignorable-coordinate analysis ([`ignorable`]) and the formulations built on them.

pub mod classical;
pub mod ignorable;
pub mod mechanics;
pub mod volterra;
