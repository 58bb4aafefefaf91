//! The scene file parser and validator on arbitrary text: must never
//! panic, only load or return an error naming the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match inference::scene::Scene::from_toml(text, Path::new("fuzz.toml")) {
        Ok(scene) => assert!(!scene.objects.is_empty()),
        Err(e) => assert!(e.to_string().contains("fuzz.toml"), "{e}"),
    }
});
