//! Scene text → `lbdem check` (parse, range checks, derived quantities, limits): must return, never panic,
//! abort or allocate scene-sized memory; a refusal must name a field (`…`) or a line.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Err(e) = lbdem::app::check_text(text, "fuzz.toml") {
        let msg = e.to_string();
        assert!(msg.contains('`') || msg.contains("line "), "names no field: {msg}");
    }
});
