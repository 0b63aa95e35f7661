#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| wraster_fuzz::checks::fixed_input(data));
