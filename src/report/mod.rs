//! Output writers: Matrix Market, VTU mode shapes, PNG charts, the report's figures and the
//! records of an engine run (JSON, text, time-series CSV).

pub mod calibration;
pub mod comparison;
pub mod figures;
pub mod maps;
pub mod mtx;
pub mod png;
pub mod records;
pub mod rom_tradeoff;
pub mod study;
pub mod summary;
pub mod vtu;
