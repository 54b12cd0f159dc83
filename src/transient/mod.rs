//! Transients: Newmark/HHT time integration, penalty contact of the piston skirts with the
//! liners, and the engine cycle on the engine ROM.

pub mod bore;
pub mod contact;
pub mod cycle;
pub mod engine;
pub mod error;
pub mod full_order;
pub mod modal;
pub mod scheme;
pub mod signal;
pub mod spectrum;
pub mod verify;
pub mod window;
