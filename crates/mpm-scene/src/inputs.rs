//! The files a scene reads (DEMs, rupture and observed rasters, CSV polylines), each with a
//! fingerprint of its contents, so that a run resumed from a checkpoint can tell whether the
//! files it reads again are the ones it started on (R3-04: a DEM rewritten between an interrupt
//! and `mpm resume` gave a run on two terrains, without a word).

use serde::{Deserialize, Serialize};

/// One file a scene read.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    /// the name the scene gives it (relative to the scene file's directory, or absolute).
    pub name: String,
    /// where it was found.
    pub path: String,
    /// FNV-1a of its bytes, 16 hex digits (`"unreadable"` if it could not be read again).
    pub fingerprint: String,
}

/// the fingerprints of `files` (name, path), each file once, in the order first named.
pub(crate) fn fingerprints(files: Vec<(String, std::path::PathBuf)>) -> Vec<InputFile> {
    let mut out: Vec<InputFile> = Vec::new();
    for (name, path) in files {
        if out.iter().any(|f| f.name == name) {
            continue;
        }
        out.push(InputFile {
            name,
            path: path.display().to_string(),
            fingerprint: fingerprint(&path).unwrap_or_else(|| "unreadable".into()),
        });
    }
    out
}

/// the folder a scene's named files are found in, `dir` (`None`: the working directory) made
/// absolute against the working directory now, when the scene is loaded (R3-04: a run resumed
/// from another working directory did not find its DEM); `None` for an embedded scene.
pub(crate) fn absolute_dir(origin: &str, dir: Option<&std::path::Path>) -> Option<String> {
    if origin.starts_with("embedded:") {
        return None;
    }
    let d = std::env::current_dir().ok()?.join(dir.unwrap_or(std::path::Path::new("")));
    Some(std::fs::canonicalize(&d).unwrap_or(d).display().to_string())
}

/// FNV-1a of the file's bytes.
fn fingerprint(path: &std::path::Path) -> Option<String> {
    let bytes = std::fs::read(path).ok()?;
    Some(format!("{:016x}", crate::fnv1a(&bytes)))
}

/// why `now` (the files a resumed run's scene read) differs from `then` (those the run started
/// on), if it does: the first file named in both whose contents changed.
pub fn changed(then: &[InputFile], now: &[InputFile]) -> Option<String> {
    then.iter().find_map(|a| {
        let b = now.iter().find(|b| b.name == a.name)?;
        (b.fingerprint != a.fingerprint).then(|| {
            format!(
                "`{}` ({}) is not the file the run started on (its contents' fingerprint was {}, \
                 is {}): the rest of the run would be on other input. Restore the file, or run \
                 the scene again",
                a.name, b.path, a.fingerprint, b.fingerprint
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file named twice is fingerprinted once; a changed file is named, an unchanged one not.
    #[test]
    fn a_changed_input_is_named_and_an_unchanged_one_passes() {
        let dir = std::env::temp_dir().join(format!("mpm-inputs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.asc"), dir.join("b.csv"));
        std::fs::write(&a, "ncols 2\n").unwrap();
        std::fs::write(&b, "0,0\n").unwrap();
        let named = || {
            vec![
                ("a.asc".into(), a.clone()),
                ("b.csv".into(), b.clone()),
                ("a.asc".into(), a.clone()),
            ]
        };
        let then = fingerprints(named());
        assert_eq!(then.len(), 2);
        assert_eq!(changed(&then, &fingerprints(named())), None);
        std::fs::write(&a, "ncols 3\n").unwrap();
        let why = changed(&then, &fingerprints(named())).unwrap();
        assert!(why.contains("`a.asc`"), "{why}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
