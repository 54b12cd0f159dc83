//! Cavitation: coolant properties, the criteria and risk classes, and the calibration of the
//! acceleration criterion from rig data.

pub mod calibration;
pub mod coolant;
pub mod criteria;
