//! The library side of the `pcaline` command: what its fuzz targets and
//! other programs call without running the binary. Configuration files
//! ([`config_file::parse`], [`config_file::resolve`]) and the command's exit
//! codes ([`exit`]).

pub mod config_file;
pub mod exit;
