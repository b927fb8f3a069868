//! Integrators and monitors.
