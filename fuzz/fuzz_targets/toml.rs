#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    shadowlab_fuzz::load(shadowlab_fuzz::Format::Toml, data);
});
