//! Mitsuba `.vol` reader on arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = niebla_volume::parse_vol(data, std::path::Path::new("fuzz.vol"));
});
