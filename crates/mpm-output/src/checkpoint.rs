//! Checkpoint files (bincode 2 with serde): the solver state, the scene text and the output
//! history, so that `mpm resume DIR` continues a run bit-identically. All bincode use is here.
//!
//! A file is a 28-byte header and a payload:
//! ```text
//! MPMCKPT\n            8 bytes, the magic
//! format               u32 little-endian ([`FORMAT`])
//! payload length       u64 little-endian (bytes)
//! payload checksum     u64 little-endian, FNV-1a 64 of the payload
//! payload              bincode (standard configuration) of `CheckpointFile`
//! ```
//! A file is trusted only after all of these hold: the magic, the format, a length equal to what
//! follows the header, and the checksum. FNV-1a changes its state by a bijection at every byte, so
//! any change confined to one byte (every single-bit flip) always changes the checksum. The
//! decoder may then claim for its collections the first power of 16 (from 1 MiB) at or above 16
//! times the payload's size, so between 16 and 256 times it (the largest expansion of any field
//! is below 16: a `u16` material index is one varint byte), so even a checksummed file with a
//! crafted length field cannot make it allocate more. What it decodes is
//! checked again against the scene before the solver takes it (`mpm_run::resume`).

use std::path::Path;

use mpm_scene::{RunoutMetrics, SavedState};
use mpm_solver::EnergyCheck;
use serde::{Deserialize, Serialize};

use crate::OutputError;
use crate::atomic;
use crate::csv::{EnergyRow, ProbeRow};

/// Format version of the checkpoint file; bumped when its layout changes (2: the history
/// carries the output time, the solver state the time step's reference densities; 3: the
/// header with length and checksum, the history the energy check; 4: particle stresses carry
/// the four plane-strain components; 5: a Drucker-Prager material that does not harden stores
/// only ε̄ᵖ per particle; 6: the dissipation carries the boundary impulse; 7: the history
/// carries the hazard envelopes; 8: the dissipation and the energy rows carry the transfer
/// dissipation, the solver settings the PIC share and the separation density; 9: the history
/// carries a 3D run's hazard maps; 10: the hazard maps no longer carry a floor height, the
/// grid's ground gives it; 11: the solver state carries each boundary's loads, the history the
/// wall-load series; 12: the dissipation and the energy rows carry the side walls' friction, the
/// solver settings the side walls, the scene registry a Mohr–Coulomb run's state; 13: no
/// layout change, but APIC's light nodes keep the particle's affine velocity, so an older APIC
/// run resumed would change its numerics mid-run; 14: the dissipation carries what left through
/// outflow faces, the energy rows its energy, the solver settings the outflow faces, the solver
/// state its mass scales, the particles their unwrapped offsets across periodic sides, the
/// history the watch over the grid's undeclared sides, a 3D run's initial centre of mass and the
/// source's top, the file the scene's folder and the fingerprints of the files it read; 15: the
/// probe rows carry z, as 3D runs have probes).
pub const FORMAT: u32 = 15;

/// The checkpoint file name inside an output directory.
pub const FILE_NAME: &str = "checkpoint.bin";

/// The first bytes of every checkpoint since format 3.
const MAGIC: &[u8; 8] = b"MPMCKPT\n";

/// Header length: magic, format, payload length, checksum.
const HEADER: usize = 8 + 4 + 8 + 8;

/// Largest checkpoint file read (bytes): 64 GiB, far above the ~200 B per particle of the
/// largest admissible scene.
const MAX_FILE: u64 = 1 << 36;

/// Everything a checkpoint holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CheckpointFile {
    /// the file format ([`FORMAT`]).
    pub format: u32,
    /// the version of the code that wrote it.
    pub code_version: String,
    /// where the scene came from (a path or `embedded:NAME`).
    pub origin: String,
    /// the scene text that ran.
    pub scene_text: String,
    /// the solver state.
    pub state: SavedState,
    /// the output written so far.
    pub history: History,
    /// the directory the scene's named files are relative to, absolute (`None`: an embedded
    /// scene), so that a run resumed from another working directory finds them.
    pub scene_dir: Option<String>,
    /// the files the scene read, with their fingerprints: a resumed run refuses a changed one.
    pub inputs: Vec<mpm_scene::inputs::InputFile>,
}

impl CheckpointFile {
    /// a checkpoint of this build ([`FORMAT`], this version) of a scene (its `origin`, text,
    /// files' folder and input files) at `state`, with the output `history` so far.
    pub fn new(
        origin: &str,
        scene_text: &str,
        scene_dir: Option<&str>,
        inputs: &[mpm_scene::inputs::InputFile],
        state: SavedState,
        history: History,
    ) -> Self {
        CheckpointFile {
            format: FORMAT,
            code_version: env!("CARGO_PKG_VERSION").to_string(),
            origin: origin.to_string(),
            scene_text: scene_text.to_string(),
            state,
            history,
            scene_dir: scene_dir.map(str::to_string),
            inputs: inputs.to_vec(),
        }
    }
}

/// writes `c` to `path` atomically, with its header.
pub fn write(path: &Path, c: &CheckpointFile) -> Result<(), OutputError> {
    let payload = bincode::serde::encode_to_vec(c, bincode::config::standard()).map_err(|e| {
        OutputError::Encode(format!("cannot encode the checkpoint {}: {e}", path.display()))
    })?;
    atomic::write_parts(path, &[&header(&payload), &payload])
}

/// the header of `payload`.
fn header(payload: &[u8]) -> Vec<u8> {
    let mut h = Vec::with_capacity(HEADER);
    h.extend_from_slice(MAGIC);
    h.extend_from_slice(&FORMAT.to_le_bytes());
    h.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    h.extend_from_slice(&mpm_scene::fnv1a(payload).to_le_bytes());
    h
}

/// reads and verifies a checkpoint file (see the module docs).
pub fn read(path: &Path) -> Result<CheckpointFile, OutputError> {
    let refuse = |reason: String| OutputError::Checkpoint { path: path.to_path_buf(), reason };
    let io = |source| OutputError::Io { path: path.to_path_buf(), source };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.file_type().is_file() {
        // a FIFO would block the open, a device such as /dev/zero never end
        return Err(refuse("not a regular file (a directory, a FIFO or a device)".into()));
    }
    let size = meta.len();
    if size > MAX_FILE {
        return Err(refuse(format!("{size} bytes, above the {MAX_FILE}-byte limit")));
    }
    // at most the length it had when looked at: a file still growing is cut, and then refused
    // by its checksum
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(
        &mut std::io::Read::take(std::fs::File::open(path).map_err(io)?, size),
        &mut bytes,
    )
    .map_err(io)?;
    let payload = verify(&bytes).map_err(refuse)?;
    let (c, used): (CheckpointFile, usize) = decode(payload)
        .map_err(|e| refuse(format!("the checksum holds but the content does not decode ({e})")))?;
    if used != payload.len() {
        return Err(refuse(format!("{} bytes after the content", payload.len() - used)));
    }
    if c.format != FORMAT {
        return Err(refuse(format!("the content claims format {}", c.format)));
    }
    Ok(c)
}

/// the payload of a checkpoint file's bytes, or why they are not one.
fn verify(bytes: &[u8]) -> Result<&[u8], String> {
    if bytes.len() < HEADER || &bytes[..8] != MAGIC {
        // Formats 1 and 2 began with the format as a bincode varint: name them as such.
        return Err(match bytes.first() {
            Some(&f @ 1..=2) => {
                format!("format {f} but this mpm reads format {FORMAT}; rerun the scene")
            }
            _ => "not an mpm checkpoint (no `MPMCKPT` header)".into(),
        });
    }
    let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or([0; 8]));
    let format = u32::from_le_bytes(bytes[8..12].try_into().unwrap_or([0; 4]));
    if format != FORMAT {
        return Err(format!("format {format} but this mpm reads format {FORMAT}; rerun the scene"));
    }
    let (length, checksum) = (word(12), word(20));
    let payload = &bytes[HEADER..];
    if length != payload.len() as u64 {
        return Err(format!(
            "truncated or extended: the header gives {length} bytes of content, the file has {}",
            payload.len()
        ));
    }
    let actual = mpm_scene::fnv1a(payload);
    if actual != checksum {
        return Err(format!(
            "corrupt: checksum {actual:016x} of the content, {checksum:016x} in the header"
        ));
    }
    Ok(payload)
}

/// decodes a verified payload, claiming for collections at most the first power of 16 at or
/// above 16 × its size (bincode's limit is a compile-time constant: one tier each).
fn decode(payload: &[u8]) -> Result<(CheckpointFile, usize), bincode::error::DecodeError> {
    use bincode::config::standard;
    use bincode::serde::decode_from_slice as from;
    match (payload.len() as u64).saturating_mul(16) {
        n if n <= 1 << 20 => from(payload, standard().with_limit::<{ 1 << 20 }>()),
        n if n <= 1 << 24 => from(payload, standard().with_limit::<{ 1 << 24 }>()),
        n if n <= 1 << 28 => from(payload, standard().with_limit::<{ 1 << 28 }>()),
        n if n <= 1 << 32 => from(payload, standard().with_limit::<{ 1 << 32 }>()),
        n if n <= 1 << 36 => from(payload, standard().with_limit::<{ 1 << 36 }>()),
        _ => from(payload, standard().with_limit::<{ 1 << 40 }>()),
    }
}

/// FNV-1a 64 hash (hex) of a value's bincode bytes: equal for bit-identical values.
pub fn state_hash<T: Serialize>(value: &T) -> String {
    let bytes =
        bincode::serde::encode_to_vec(value, bincode::config::standard()).unwrap_or_default();
    format!("{:016x}", mpm_scene::fnv1a(&bytes))
}

/// Output history carried in checkpoints so that a resumed run continues its files.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct History {
    /// the rows of `energy.csv`.
    pub energy: Vec<EnergyRow>,
    /// the rows of `probes.csv`.
    pub probes: Vec<ProbeRow>,
    /// the rows of `runout.csv`.
    pub runout: Vec<RunoutMetrics>,
    /// (time, file relative to the output directory).
    pub frames: Vec<(f64, String)>,
    /// index k of the last frame time k·interval taken.
    pub frame_slot: u64,
    /// index k of the last series time k·interval taken.
    pub series_slot: u64,
    /// index k of the last checkpoint time k·interval taken.
    pub checkpoint_slot: u64,
    /// smallest Δt so far (s).
    pub dt_min: f64,
    /// largest Δt so far (s).
    pub dt_max: f64,
    /// the first Δt (s).
    pub dt_first: f64,
    /// wall time of earlier sessions (s).
    pub wall_time: f64,
    /// particle-steps of earlier sessions.
    pub particle_steps: f64,
    /// wall time spent writing frames and time series, over all sessions (s).
    #[serde(default)]
    pub output_time: f64,
    /// the runout measures at t = 0.
    pub initial: Option<RunoutMetrics>,
    /// the energy residual against its scale, from the first series row on.
    #[serde(default)]
    pub energy_check: Option<EnergyCheck>,
    /// when the energy alarm first tripped (s).
    #[serde(default)]
    pub alarm_time: Option<f64>,
    /// the hazard envelopes so far, when the scene asks for them.
    #[serde(default)]
    pub envelope: Option<mpm_scene::envelope::Envelope>,
    /// a 3D run's hazard maps so far, when the scene asks for them.
    #[serde(default)]
    pub plan: Option<mpm_scene::plan::PlanEnvelope>,
    /// the rows of `walls.csv` so far, when the scene has a boundary.
    #[serde(default)]
    pub walls: Option<crate::loads::WallSeries>,
    /// the watch over the grid's side faces that the scene did not declare.
    #[serde(default)]
    pub edges: Option<mpm_scene::edges::EdgeWatch>,
    /// a 3D run's centre of mass at t = 0 (m): the reference of its travel, kept because
    /// particles may leave the run through outflow sides.
    #[serde(default)]
    pub initial_centre: Option<[f64; 3]>,
    /// the highest particle at t = 0 (m; z = 0 in 2D): the source's top for the travel angle,
    /// kept because particles may leave the run through outflow sides.
    #[serde(default)]
    pub crown: Option<[f64; 3]>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_single_bit_flip_of_a_file_is_refused_before_decoding() {
        let payload: Vec<u8> = (0..200u32).map(|i| (i * 37 % 251) as u8).collect();
        let mut file = header(&payload);
        file.extend_from_slice(&payload);
        assert_eq!(verify(&file), Ok(&payload[..]));
        for bit in 0..file.len() * 8 {
            let mut flipped = file.clone();
            flipped[bit / 8] ^= 1 << (bit % 8);
            assert!(verify(&flipped).is_err(), "bit {bit} went unnoticed");
        }
        // truncated by one byte, or one byte appended
        assert!(verify(&file[..file.len() - 1]).unwrap_err().contains("truncated"));
        let mut longer = file.clone();
        longer.push(0);
        assert!(verify(&longer).unwrap_err().contains("truncated"));
    }

    #[test]
    fn a_crafted_length_cannot_claim_more_than_the_payloads_tier() {
        // A checksummed payload whose first field (the format, 3) is followed by a string length
        // of 2^40 (varint 0xFD + u64): decoding must fail on the limit, not try to allocate.
        let mut payload = vec![3u8, 0xFD];
        payload.extend_from_slice(&(1u64 << 40).to_le_bytes());
        let e = decode(&payload).unwrap_err();
        assert!(matches!(e, bincode::error::DecodeError::LimitExceeded), "{e:?}");
    }
}
