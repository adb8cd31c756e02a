//! Bundled scene texts and one-key edits of them, for the tests that feed scenes to `lbdem` (hostile input,
//! scene keys).
use std::path::Path;

/// The folder of the bundled scenes.
pub const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes");

/// The text of the bundled scene `scenes/NAME`.
pub fn scene(name: &str) -> String {
    std::fs::read_to_string(Path::new(SCENES).join(name)).unwrap()
}

/// `text` with the value of the first line whose key is `key` replaced by `value` (the key must exist).
pub fn with(text: &str, key: &str, value: &str) -> String {
    let mut done = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            let k = l.split('=').next().unwrap_or_default().trim();
            if !done && l.contains('=') && k == key {
                done = true;
                format!("{key} = {value}")
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(done, "no key {key}");
    out.join("\n") + "\n"
}
