//! Integration tests of the `mpm` front end: the malformed-scene corpus, the embedded scenes,
//! short runs and their files, resume bit-identity, and the binary's commands.

mod binary;
mod guards;
mod malformed;
mod runs;
mod scenes;

use std::path::PathBuf;

/// A fresh, unique directory path under the system temp dir (not created).
pub fn temp_dir(name: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    std::env::temp_dir().join(format!("mpm-cli-test-{}-{name}-{nanos}", std::process::id()))
}
