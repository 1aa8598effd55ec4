//! File readers. Each reads the whole file into memory and parses it with a
//! bounds-checked cursor ([`bytes::ByteReader`]).

pub(crate) mod blosc;
pub(crate) mod bytes;
pub mod npy;
pub mod vdb;
pub mod vol;
