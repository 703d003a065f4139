//! What made a run folder: `run.json` and `settings.resolved.toml` beside the frames.
//!
//! `settings.resolved.toml` holds the resolved settings, every key with its value after `--set` and the
//! defaults (`shellsim RUN/settings.resolved.toml MESH` runs the same scene again). `run.json` holds a
//! list `runs`, one entry per invocation that wrote into the folder (a run continued with
//! `--continue` adds one): the shellsim version and git commit, the command line and working
//! folder, the settings file and the overrides, the mesh's path, size and SHA-256, the restart
//! frame, the threads, the host, the start and end times (RFC 3339, UTC), and at the end the
//! outcome (`status`, `reason`, `exit_code`, `frames`, `wall_seconds`). An entry whose `status`
//! is still `"running"` belongs to a run that was killed.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// A file's path (absolute where it can be made so), size and SHA-256 (hex).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FileRecord {
    /// The path as given on the command line.
    pub path: String,
    /// The absolute path.
    pub absolute: String,
    /// Size in bytes.
    pub bytes: u64,
    /// SHA-256 of the contents, lower-case hex.
    pub sha256: String,
}

impl FileRecord {
    /// Reads `path` to record it.
    pub fn of(path: &Path) -> std::io::Result<Self> {
        let data = std::fs::read(path)?;
        let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        Ok(FileRecord {
            path: path.display().to_string(),
            absolute: absolute.display().to_string(),
            bytes: data.len() as u64,
            sha256: sha256_hex(&data),
        })
    }
}

/// SHA-256 of `data` as lower-case hex.
pub fn sha256_hex(data: &[u8]) -> String {
    Sha256::digest(data)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// One invocation that wrote into a run folder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunRecord {
    /// `CARGO_PKG_VERSION` of the binary.
    pub shellsim_version: String,
    /// The git commit the binary was built from (`-dirty`: with uncommitted changes).
    pub commit: String,
    /// The command line, one string per argument.
    pub command_line: Vec<String>,
    /// The working folder.
    pub working_folder: String,
    /// The settings file as given.
    pub settings: FileRecord,
    /// The `--set` overrides, in order.
    pub overrides: Vec<String>,
    /// The resolved settings, in this folder.
    pub resolved_settings: String,
    /// The mesh file.
    pub mesh: FileRecord,
    /// Vertices and faces of the mesh.
    pub vertices: usize,
    /// See `vertices`.
    pub faces: usize,
    /// The frame the run started from (`--restart`, `--continue`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart: Option<FileRecord>,
    /// The mesh obstacles' files (`[[obstacles]]` with `shape = "mesh"`), in their order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacle_meshes: Vec<FileRecord>,
    /// Worker threads.
    pub threads: usize,
    /// The machine's host name.
    pub host: String,
    /// When the run started (RFC 3339, UTC).
    pub started: String,
    /// When it ended (RFC 3339, UTC); absent while it runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ended: Option<String>,
    /// `"running"`, `"converged"`, `"not converged"`, `"interrupted"` or `"failed"` (an error
    /// stopped it).
    pub status: String,
    /// Why it stopped, when it did not converge.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub reason: String,
    /// The process's exit code, once ended.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exit_code: Option<u8>,
    /// Frames this invocation wrote.
    #[serde(default)]
    pub frames: usize,
    /// Its wall time (s).
    #[serde(default)]
    pub wall_seconds: f64,
}

/// The contents of `run.json`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Provenance {
    /// Every invocation that wrote into the folder, oldest first.
    pub runs: Vec<RunRecord>,
}

/// The current time as RFC 3339 in UTC, to the second.
pub fn now() -> String {
    humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string()
}

/// The host name (empty when it cannot be read).
pub fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// The commit recorded at build time.
pub fn commit() -> &'static str {
    env!("SHELLSIM_COMMIT")
}

/// `run.json` of `dir`.
pub fn path(dir: &Path) -> PathBuf {
    dir.join("run.json")
}

/// Reads `dir/run.json`: `None` when there is none; an unreadable one is an error.
pub fn read(dir: &Path) -> Result<Option<Provenance>, String> {
    let p = path(dir);
    match std::fs::read_to_string(&p) {
        Ok(t) => serde_json::from_str(&t)
            .map(Some)
            .map_err(|e| format!("{}: {e}", p.display())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(format!("{}: {e}", p.display())),
    }
}

/// Writes `dir/run.json` atomically.
pub fn write(dir: &Path, p: &Provenance) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(p).map_err(std::io::Error::other)?;
    crate::mesh::io::write_atomic(&path(dir), text.as_bytes())
}
