//! The tessellation store: what Open CASCADE returned for a STEP file, kept in a folder
//! (a project's [`super::STEP_STORE`]) so that a later read of the same bytes with the
//! same tessellation skips Open CASCADE — and the rules that keep it from growing
//! without end.
//!
//! **Entries.** One file `<16 hex digits>.tess` per STEP content (its hash and length)
//! and tessellation (linear and angular deflection); it records the STEP file it was
//! read from (its canonical path). Entries are written by the project's write rule
//! ([`crate::project::write_output`]: a temporary file renamed into place), so a reader
//! never sees half an entry, and a file there that fitup did not write is never
//! replaced. A hit refreshes the entry's modification time: its last use.
//!
//! **What removes an entry** (never anything but fitup's own entries and its own
//! leftover temporary files, and only inside the store folder):
//! - *on write* of an entry for a source, the entries recorded for the same source
//!   with other contents: that file changed, they can never be hit from it again; and
//!   then, while the store is over its size cap ([`DEFAULT_STORE_CAP`]), the least
//!   recently used entries (never the one just written);
//! - *on [`prune_store`]* (`fitup cache prune`): entries whose source is gone or
//!   changed, entries of the old format or damaged, entries whose tessellation no
//!   document asks for any more (when the caller knows, [`PruneOptions::in_use`]),
//!   temporary files left by a writer that died an hour or more ago, and then the
//!   least recently used down to [`PruneOptions::max_bytes`].
//!
//! Writers' sweeps and pruners take turns on the folder's lock ([`crate::fsutil::lock_folder`]);
//! readers take no lock: removing an entry only unlinks it (a reader that has it open
//! reads it whole; one that comes later misses and reads the STEP file again).

use super::raw::{decode_model_within, encode_model_peak, Bad, RawModel, Reader, Writer};
use super::StepOptions;
use crate::fsutil::{Dir, FileKind, Kind};
use std::collections::{HashMap, HashSet};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// How an entry begins (format 3: with the source's path and the assembly tree;
/// format 2 had no assemblies).
const STORE_MAGIC: &[u8] = b"fitup-tessellation 3\n";

/// What every format of entry begins with (format 1 had no source).
const ANY_STORE_MAGIC: &[u8] = b"fitup-tessellation ";

/// The default size cap of a store, bytes (1 GiB): past it, writing an entry evicts the
/// least recently used.
pub const DEFAULT_STORE_CAP: u64 = 1 << 30;

/// The longest source path an entry records, bytes.
const MAX_SOURCE_BYTES: usize = 4096;

/// How old a writer's temporary file must be before [`prune_store`] takes it for a
/// leftover of a writer that died (a live writer renames it within seconds).
const LEFTOVER_AGE: Duration = Duration::from_secs(3600);

/// What a stored tessellation is of: the STEP bytes (their hash and length) and the
/// deflection and angle it was meshed with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct StoreKey {
    hash: u64,
    len: u64,
    linear: u64,
    angular: u64,
}

impl StoreKey {
    pub(super) fn new(bytes: &[u8], options: &StepOptions) -> StoreKey {
        StoreKey {
            hash: crate::fsutil::content_hash(bytes),
            len: bytes.len() as u64,
            linear: options.linear_deflection.to_bits(),
            angular: options.angular_deflection.to_bits(),
        }
    }

    /// The stored file's name: the key, hashed.
    fn file_name(&self) -> String {
        let mut w = Writer::default();
        self.write(&mut w);
        format!("{:016x}.tess", crate::fsutil::content_hash(&w.0))
    }

    fn write(&self, w: &mut Writer) {
        for v in [self.hash, self.len, self.linear, self.angular] {
            w.u64(v);
        }
    }

    fn read(r: &mut Reader) -> Result<StoreKey, Bad> {
        Ok(StoreKey {
            hash: r.u64()?,
            len: r.u64()?,
            linear: r.u64()?,
            angular: r.u64()?,
        })
    }
}

/// The source as an entry records it: its canonical path, as UTF-8 (empty when it has
/// none or is too long: such an entry is never taken for any file's).
fn source_text(source: &Path) -> String {
    source
        .canonicalize()
        .ok()
        .and_then(|p| p.to_str().map(str::to_string))
        .filter(|s| s.len() <= MAX_SOURCE_BYTES)
        .unwrap_or_default()
}

/// The largest entry read, bytes (256 MiB, [`FileKind::Mesh`]'s cap; ≈ 10 million
/// triangles of a closed solid). A larger file is not read (a miss) and is removed.
/// An entry is decoded as it is read (a 1 MiB buffer, never the file whole), a part
/// past [`MAX_TRIANGLES`](crate::mesh::MAX_TRIANGLES) refused from its count before it
/// is allocated, and the meshes welded without a corner soup: a stored read takes
/// the decoded model (at most about the entry's size) and then its meshes
/// (docs/document.md, "What reading takes").
pub const MAX_ENTRY_BYTES: u64 = FileKind::Mesh.max_bytes();

/// The store folder held open, walked from the folder that holds it without following
/// a link (`.fitup-cache/step` below the project root: a link at `.fitup-cache` or
/// `step` is refused, so the store cannot be pointed outside the project); with
/// `create`, made when missing.
pub(super) fn open_store(store: &Path, create: bool) -> std::io::Result<Dir> {
    let depth = Path::new(super::STEP_STORE).components().count();
    let (base, rel) = if store.ends_with(super::STEP_STORE) {
        let mut base = store;
        for _ in 0..depth {
            base = base.parent().unwrap_or(base);
        }
        (base, Path::new(super::STEP_STORE))
    } else {
        let name = store
            .file_name()
            .ok_or_else(|| std::io::Error::other("the store has no folder name"))?;
        (store.parent().unwrap_or(Path::new(".")), Path::new(name))
    };
    let base = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    Dir::open(base)?.walk(rel, create)
}

/// The stored tessellation for `key` in `store`, when present and sound (anything
/// else — missing, another key, the old format — is a miss). An entry that is a
/// symbolic link, larger than [`MAX_ENTRY_BYTES`], cut, or poisoned (a coordinate
/// that is not finite or beyond [`MAX_ABS_VALUE`](crate::math::MAX_ABS_VALUE), an
/// index past its vertices, a placement that is not finite) is removed and
/// is a miss: the STEP file is read again and the entry rebuilt; the STEP file is
/// never blamed for what the store holds. A hit marks the entry used now.
pub(super) fn load_stored(store: &Path, key: &StoreKey) -> Option<RawModel> {
    let dir = open_store(store, false).ok()?;
    let name = key.file_name();
    let name = OsStr::new(&name);
    // Removes what is at the name when it is a link (the link itself) or fitup's
    // (begins with the store's magic): never a file someone else put there.
    let bad = |dir: &Dir| {
        // Under the folder's lock: a sweep or a prune is not racing on the same name.
        let _turn = dir.lock();
        let ours = match dir.stat(name) {
            Ok(Some(Kind::Symlink)) => true,
            Ok(Some(Kind::File(_))) => {
                use std::io::Read;
                let mut head = Vec::new();
                dir.open_file(name)
                    .and_then(|f| f.take(ANY_STORE_MAGIC.len() as u64).read_to_end(&mut head))
                    .is_ok()
                    && head.starts_with(ANY_STORE_MAGIC)
            }
            _ => false,
        };
        if ours {
            let _ = dir.remove(name);
        }
        None
    };
    match dir.stat(name) {
        Ok(Some(Kind::File(len))) if len <= MAX_ENTRY_BYTES => {}
        Ok(None) | Err(_) => return None,
        Ok(Some(_)) => return bad(&dir),
    }
    // Decoded as it is read (never held whole): a count past its part's cap or past
    // the bytes left is refused before anything is allocated for it.
    let Ok(file) = dir.open_file(name) else {
        return bad(&dir);
    };
    let Ok(len) = file.metadata().map(|m| m.len()) else {
        return bad(&dir);
    };
    if len > MAX_ENTRY_BYTES {
        return bad(&dir);
    }
    let mut r = Reader::stream(file, len);
    match r.take(STORE_MAGIC.len()) {
        Ok(m) if m == STORE_MAGIC => {}
        _ => return None, // not this format: prune's business
    }
    match StoreKey::read(&mut r) {
        Ok(k) if k == *key => {}
        Ok(_) => return None,
        Err(_) => return bad(&dir),
    }
    let decoded = r
        .str()
        .and_then(|_| decode_model_within(&mut r, crate::mesh::MAX_TRIANGLES))
        .and_then(|m| {
            if r.is_empty() {
                Ok(m)
            } else {
                Err("bytes after the model")
            }
        })
        .and_then(|m| sound(&m).map(|()| m));
    drop(r);
    match decoded {
        Ok(model) => {
            touch(&dir, name);
            Some(model)
        }
        Err(_) => bad(&dir),
    }
}

/// Whether a decoded entry can be what Open CASCADE returned: coordinates finite and
/// in range, indices within their part's vertices, placements finite and of a part
/// that exists, volumes finite.
fn sound(m: &RawModel) -> Result<(), Bad> {
    let max = crate::math::MAX_ABS_VALUE;
    for p in &m.parts {
        if p.vertices.len() % 3 != 0 || p.triangles.len() % 3 != 0 {
            return Err("a partial vertex or triangle");
        }
        if p.vertices.iter().any(|v| !v.is_finite() || v.abs() > max) {
            return Err("a coordinate that is not finite or out of range");
        }
        let n = (p.vertices.len() / 3) as u64;
        if p.triangles.iter().any(|&i| u64::from(i) >= n) {
            return Err("an index past the vertices");
        }
        if !p.exact_volume.is_finite() {
            return Err("a volume that is not finite");
        }
    }
    for i in &m.instances {
        if i.part as usize >= m.parts.len()
            || !i.scale.is_finite()
            || i.matrix.iter().any(|v| !v.is_finite() || v.abs() > max)
        {
            // (Whether it is a rigid motion is the model's check: a stored model
            // that fails it is discarded by the reader, `read_step_stored`.)
            return Err("a placement that is not finite or names no stored part");
        }
        if i.parent as usize > m.assemblies.len() {
            return Err("a solid in an assembly that is not stored");
        }
    }
    for (k, a) in m.assemblies.iter().enumerate() {
        if a.parent as usize > k
            || !a.scale.is_finite()
            || a.matrix.iter().any(|v| !v.is_finite() || v.abs() > max)
        {
            return Err("an assembly placement that is not finite or not below its parent");
        }
    }
    Ok(())
}

/// Removes the entry for `key` (one that did not make a model: damaged).
pub(super) fn discard(store: &Path, key: &StoreKey) {
    if let Ok(dir) = open_store(store, false) {
        let _turn = dir.lock();
        let _ = dir.remove(OsStr::new(&key.file_name()));
    }
}

/// Marks the entry `name` used now (its modification time), unless it was within the
/// last minute; failures only make it look older to the size cap.
fn touch(dir: &Dir, name: &OsStr) {
    let now = SystemTime::now();
    if let Ok(f) = dir.open_file_rw(name) {
        let recent = f.metadata().and_then(|m| m.modified()).is_ok_and(|t| {
            now.duration_since(t)
                .is_ok_and(|d| d < Duration::from_secs(60))
        });
        if !recent {
            let _ = f.set_modified(now);
        }
    }
}

/// Keeps `model` for `key` (read from the STEP file `source`) in `store`, through the
/// write rule (a file there that fitup did not write is left alone), then removes what
/// the write made stale: the entries of `source` with other contents, and the least
/// recently used while the store holds more than `cap` bytes. Everything goes through
/// the store folder held open (never through a link). Failures are ignored: the store
/// only saves time.
pub(super) fn store(store: &Path, key: &StoreKey, source: &Path, model: &RawModel, cap: u64) {
    let Ok(dir) = open_store(store, true) else {
        return;
    };
    let source = source_text(source);
    let mut w = Writer(STORE_MAGIC.to_vec());
    key.write(&mut w);
    w.str(&source);
    // The reader's peak memory is not kept (written as 0, rather than encoding a copy
    // of the model: that doubled the store's cost).
    encode_model_peak(&mut w, model, 0);
    if w.0.len() as u64 > MAX_ENTRY_BYTES {
        return; // never read back: not kept
    }
    let rule = crate::project::OutputRule {
        signature: Some(ANY_STORE_MAGIC),
        ..crate::project::OutputRule::forced(false)
    };
    let name = key.file_name();
    let os_name = OsStr::new(&name);
    // A link planted at the entry's name is removed first (the write rule would
    // refuse to write over it, and the entry would never be kept again).
    if matches!(dir.stat(os_name), Ok(Some(Kind::Symlink))) {
        let _ = dir.remove(os_name);
    }
    if crate::project::check_output_in(&dir, os_name, &store.join(&name), &rule).is_err()
        || crate::project::write_in(&dir, os_name, &w.0).is_err()
    {
        return;
    }
    // The sweep takes turns with other writers' sweeps and with prune (the write
    // itself cannot: the write rule's registry takes the same folder lock).
    let _turn = dir.lock();
    let Ok(found) = scan(&dir) else { return };
    let mut kept = Vec::new();
    for e in found.entries {
        let changed = matches!(&e.header, Ok(h) if !source.is_empty()
            && h.source == source
            && (h.key.hash, h.key.len) != (key.hash, key.len));
        if changed {
            let _ = dir.remove(OsStr::new(&e.name));
        } else if e.name != name {
            kept.push(e);
        }
    }
    let total: u64 = kept.iter().map(|e| e.bytes).sum::<u64>() + w.0.len() as u64;
    for e in over_cap(kept, total, cap) {
        let _ = dir.remove(OsStr::new(&e.name));
    }
}

/// An entry's head: its key and source.
#[derive(Debug, Clone)]
struct Header {
    key: StoreKey,
    source: String,
}

/// A file of the store that fitup wrote (it begins with the store's magic).
#[derive(Debug)]
struct Found {
    file: PathBuf,
    name: String,
    bytes: u64,
    modified: SystemTime,
    /// The head; `Err` for the old format or a damaged head.
    header: Result<Header, StaleReason>,
}

/// What [`scan`] found: fitup's entries and its writers' temporary files (with their
/// age); everything else in the folder is not fitup's and is left out.
struct Scan {
    entries: Vec<Found>,
    leftovers: Vec<(PathBuf, u64, SystemTime)>,
}

/// The entries and leftovers of `store`. Only regular files are looked at (a symbolic
/// link is never followed), named as an entry (`<16 hex digits>.tess`) and beginning
/// with the store's magic, or as a writer's temporary file (`.fitup-*.tmp`).
fn scan(dir: &Dir) -> std::io::Result<Scan> {
    use std::io::Read;
    let mut out = Scan {
        entries: Vec::new(),
        leftovers: Vec::new(),
    };
    for (name, kind) in dir.entries()? {
        if !matches!(kind, Kind::File(_)) {
            continue;
        }
        let name = name.to_string_lossy().into_owned();
        let os_name = OsStr::new(&name);
        let Ok(file) = dir.open_file(os_name) else {
            continue;
        };
        let Ok(md) = file.metadata() else { continue };
        let modified = md.modified().unwrap_or(SystemTime::UNIX_EPOCH);
        let path = dir.path().join(&name);
        if name.starts_with(".fitup-") && name.ends_with(".tmp") {
            out.leftovers.push((path, md.len(), modified));
            continue;
        }
        let is_entry_name = name.len() == 21
            && name.ends_with(".tess")
            && name.as_bytes()[..16].iter().all(u8::is_ascii_hexdigit);
        if !is_entry_name {
            continue;
        }
        let mut head = Vec::new();
        if file
            .take((MAX_SOURCE_BYTES + 128) as u64)
            .read_to_end(&mut head)
            .is_err()
        {
            continue;
        }
        if !head.starts_with(ANY_STORE_MAGIC) {
            continue; // not fitup's
        }
        let header = match head.strip_prefix(STORE_MAGIC) {
            None => Err(StaleReason::OldFormat),
            Some(rest) => {
                let mut r = Reader::new(rest);
                match (StoreKey::read(&mut r), r.str()) {
                    (Ok(key), Ok(source)) => Ok(Header { key, source }),
                    _ => Err(StaleReason::Damaged),
                }
            }
        };
        out.entries.push(Found {
            file: path,
            name,
            bytes: md.len(),
            modified,
            header,
        });
    }
    Ok(out)
}

/// The entries to evict so that `kept` (holding `total` bytes with what else the store
/// keeps) fits in `cap`: the least recently used first.
fn over_cap(mut kept: Vec<Found>, mut total: u64, cap: u64) -> Vec<Found> {
    kept.sort_by_key(|e| e.modified);
    let mut evict = Vec::new();
    for e in kept {
        if total <= cap {
            break;
        }
        total -= e.bytes;
        evict.push(e);
    }
    evict
}

/// Why [`prune_store`] removes a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum StaleReason {
    /// The STEP file it was read from is gone.
    SourceGone,
    /// The STEP file it was read from has other contents now.
    SourceChanged,
    /// The STEP file it names is outside the project that holds the store (a forged
    /// or moved entry): never opened.
    SourceOutside,
    /// Written by an older fitup (no source recorded): never read any more.
    OldFormat,
    /// Its head is cut or garbled.
    Damaged,
    /// No document asks for this file with this tessellation any more (another
    /// `deflection:` or `angle:`, or the part is gone).
    Unused,
    /// Least recently used while the store was over its size cap.
    OverCap,
    /// A temporary file a writer left when it died.
    Leftover,
}

impl std::fmt::Display for StaleReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            StaleReason::SourceGone => "its STEP file is gone",
            StaleReason::SourceChanged => "its STEP file changed",
            StaleReason::SourceOutside => "it names a file outside the project",
            StaleReason::OldFormat => "an older fitup's format",
            StaleReason::Damaged => "damaged",
            StaleReason::Unused => "no document uses this tessellation",
            StaleReason::OverCap => "least recently used, over the size cap",
            StaleReason::Leftover => "a dead writer's temporary file",
        })
    }
}

/// What a tessellation is of, as documents ask for it: the STEP file's canonical path
/// and the linear and angular deflection (mm, radians) as [`StepOptions`] holds them.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Tessellation {
    /// The STEP file (canonical).
    pub source: PathBuf,
    /// [`StepOptions::linear_deflection`]'s bits.
    pub linear_bits: u64,
    /// [`StepOptions::angular_deflection`]'s bits.
    pub angular_bits: u64,
}

impl Tessellation {
    /// The tessellation of `source` with `linear` (mm) and `angular` (radians)
    /// deflection; `None` when `source` does not exist.
    pub fn new(source: &Path, linear: f64, angular: f64) -> Option<Self> {
        Some(Tessellation {
            source: source.canonicalize().ok()?,
            linear_bits: linear.to_bits(),
            angular_bits: angular.to_bits(),
        })
    }
}

/// How [`prune_store`] prunes.
#[derive(Debug, Clone)]
pub struct PruneOptions {
    /// Only say what would be removed.
    pub dry_run: bool,
    /// The size the store is brought down to, bytes (least recently used first).
    pub max_bytes: u64,
    /// The tessellations the project's documents ask for: an entry of a current
    /// source that is not among them is removed. `None`: not known (an unreadable
    /// document); such entries are kept.
    pub in_use: Option<HashSet<Tessellation>>,
}

impl Default for PruneOptions {
    fn default() -> Self {
        PruneOptions {
            dry_run: false,
            max_bytes: DEFAULT_STORE_CAP,
            in_use: None,
        }
    }
}

/// A file [`prune_store`] removed (or would remove).
#[derive(Debug, Clone, PartialEq)]
pub struct Pruned {
    /// The file in the store.
    pub file: PathBuf,
    /// Its size, bytes.
    pub bytes: u64,
    /// Why.
    pub reason: StaleReason,
    /// The STEP file it was read from, when recorded.
    pub source: Option<PathBuf>,
    /// Its tessellation's linear deflection (mm), when the head is readable.
    pub deflection: Option<f64>,
}

/// What [`prune_store`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PruneReport {
    /// Removed (with [`PruneOptions::dry_run`]: would be removed).
    pub removed: Vec<Pruned>,
    /// Entries kept, and their bytes.
    pub kept: usize,
    /// Bytes of the kept entries.
    pub kept_bytes: u64,
    /// Files that could not be removed, and why.
    pub failed: Vec<(PathBuf, std::io::ErrorKind)>,
}

/// Why a store could not be pruned (nothing was removed).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// The store's path is a symbolic link or not a folder: pruning it could reach
    /// outside the project.
    #[error("{}: the tessellation store is not a folder (a symbolic link or a file): refusing to prune it", path.display())]
    NotAFolder {
        /// The store.
        path: PathBuf,
    },
    /// The folder could not be listed.
    #[error("{}: cannot list the tessellation store: {kind}", path.display())]
    Io {
        /// The store.
        path: PathBuf,
        /// The operating system's answer.
        kind: std::io::ErrorKind,
    },
}

/// What [`prune_store`] knows of the sources entries name: each file looked at (and
/// hashed, streaming) at most once per prune, however many entries name it; only files
/// inside the project, reached from its folder without following a link.
struct Sources {
    /// The project folder (the store's owner), canonical and held open; `None`: it
    /// cannot be opened (every source then counts as current).
    root: Option<(PathBuf, Dir)>,
    seen: HashMap<String, Seen>,
}

/// What [`Sources`] found of one source path.
#[derive(Clone, Copy)]
enum Seen {
    /// Gone, outside the project, or not a regular file.
    Stale(StaleReason),
    /// A regular file of this length; its hash once computed.
    File { len: u64, hash: Option<u64> },
    /// Could not be looked at (kept).
    Unknown,
}

impl Sources {
    /// The project folder of `store`, looked up by its name (for [`prune_store`], given
    /// a path; a project's prune hands its held root to [`prune_held`] instead).
    fn root_by_name(store: &Path) -> Option<(PathBuf, Dir)> {
        let depth = Path::new(super::STEP_STORE).components().count();
        let root = if store.ends_with(super::STEP_STORE) {
            store.ancestors().nth(depth).map(Path::to_path_buf)
        } else {
            store.parent().map(Path::to_path_buf)
        };
        root.and_then(|r| r.canonicalize().ok())
            .and_then(|r| Dir::open(&r).ok().map(|d| (r, d)))
    }

    /// Whether the source an entry records is the file it was read from: `None` when
    /// it is, else why not. A source outside the project is never opened (stale: a
    /// project's store names only the project's files); one that cannot be looked at
    /// for another reason counts as current (kept).
    fn state(&mut self, h: &Header) -> Option<StaleReason> {
        if h.source.is_empty() {
            return Some(StaleReason::SourceGone);
        }
        let seen = match self.seen.get(&h.source) {
            Some(s) => *s,
            None => {
                let s = self.look(&h.source);
                self.seen.insert(h.source.clone(), s);
                s
            }
        };
        match seen {
            Seen::Stale(r) => Some(r),
            Seen::Unknown => None,
            Seen::File { len, .. } if len != h.key.len => Some(StaleReason::SourceChanged),
            Seen::File { len, hash } => {
                let hash = match hash {
                    Some(x) => Some(x),
                    None => {
                        let x = self.hash(&h.source);
                        self.seen
                            .insert(h.source.clone(), Seen::File { len, hash: x });
                        x
                    }
                };
                match hash {
                    Some(x) if x != h.key.hash => Some(StaleReason::SourceChanged),
                    _ => None,
                }
            }
        }
    }

    /// The folder of `source` (inside the root) held open, and the file's name.
    fn folder(&self, source: &str) -> Result<(Dir, std::ffi::OsString), Seen> {
        let Some((root, dir)) = &self.root else {
            return Err(Seen::Unknown);
        };
        let Ok(rel) = Path::new(source).strip_prefix(root) else {
            return Err(Seen::Stale(StaleReason::SourceOutside));
        };
        let (Some(parent), Some(name)) = (rel.parent(), rel.file_name()) else {
            return Err(Seen::Stale(StaleReason::SourceGone));
        };
        match dir.walk(parent, false) {
            Ok(d) => Ok((d, name.to_os_string())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                Err(Seen::Stale(StaleReason::SourceGone))
            }
            // A link (or a file) where a folder was: not the file it was read from.
            Err(e) if e.kind() == std::io::ErrorKind::Other => {
                Err(Seen::Stale(StaleReason::SourceGone))
            }
            Err(_) => Err(Seen::Unknown),
        }
    }

    fn look(&self, source: &str) -> Seen {
        let (dir, name) = match self.folder(source) {
            Ok(f) => f,
            Err(seen) => return seen,
        };
        match dir.stat(&name) {
            Ok(Some(Kind::File(len))) => Seen::File { len, hash: None },
            Ok(_) => Seen::Stale(StaleReason::SourceGone),
            Err(_) => Seen::Unknown,
        }
    }

    /// The content hash of `source`, streamed (never read whole), through its held
    /// folder without following a link.
    fn hash(&self, source: &str) -> Option<u64> {
        let (dir, name) = self.folder(source).ok()?;
        let f = dir.open_file(&name).ok()?;
        crate::fsutil::hash_reader(f).ok().map(|(_, h)| h)
    }
}

/// Removes the stale files of the store folder `store` (see the module documentation
/// for the rules), or with [`PruneOptions::dry_run`] only lists them. A store that does
/// not exist is empty. Only fitup's entries and its writers' leftovers inside `store`
/// are ever removed, through the store folder held open; `store` must be a real folder
/// (reached without a symbolic link). The sources entries name are looked at only
/// inside the project that holds the store, each once.
pub fn prune_store(store: &Path, options: &PruneOptions) -> Result<PruneReport, StoreError> {
    let dir = match open_store(store, false) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(PruneReport::default()),
        Err(e) if e.kind() == std::io::ErrorKind::Other => {
            return Err(StoreError::NotAFolder { path: store.into() })
        }
        Err(e) => {
            return Err(StoreError::Io {
                path: store.into(),
                kind: e.kind(),
            })
        }
    };
    prune_held(store, dir, Sources::root_by_name(store), options)
}

/// [`prune_store`] of the store folder `dir` (held open; `store` its path, for the
/// report), the sources its entries name looked at only inside `root` (the project
/// folder, canonical, held open; `None`: every source counts as current).
pub(crate) fn prune_held(
    store: &Path,
    dir: Dir,
    root: Option<(PathBuf, Dir)>,
    options: &PruneOptions,
) -> Result<PruneReport, StoreError> {
    let mut report = PruneReport::default();
    let _turn = dir.lock();
    let found = scan(&dir).map_err(|e| StoreError::Io {
        path: store.into(),
        kind: e.kind(),
    })?;
    let mut sources = Sources {
        root,
        seen: HashMap::new(),
    };
    let mut stale = Vec::new();
    let now = SystemTime::now();
    for (file, bytes, modified) in found.leftovers {
        if now
            .duration_since(modified)
            .is_ok_and(|age| age >= LEFTOVER_AGE)
        {
            stale.push(Pruned {
                file,
                bytes,
                reason: StaleReason::Leftover,
                source: None,
                deflection: None,
            });
        }
    }
    let mut kept = Vec::new();
    for e in found.entries {
        let reason = match &e.header {
            Err(r) => Some(*r),
            Ok(h) => sources.state(h).or_else(|| {
                let t = Tessellation {
                    source: PathBuf::from(&h.source),
                    linear_bits: h.key.linear,
                    angular_bits: h.key.angular,
                };
                options
                    .in_use
                    .as_ref()
                    .is_some_and(|u| !u.contains(&t))
                    .then_some(StaleReason::Unused)
            }),
        };
        match reason {
            Some(reason) => stale.push(pruned(&e, reason)),
            None => kept.push(e),
        }
    }
    let total: u64 = kept.iter().map(|e| e.bytes).sum();
    report.kept = kept.len();
    let evicted = over_cap(kept, total, options.max_bytes);
    report.kept -= evicted.len();
    report.kept_bytes = total - evicted.iter().map(|e| e.bytes).sum::<u64>();
    for e in &evicted {
        stale.push(pruned(e, StaleReason::OverCap));
    }
    for p in stale {
        if !options.dry_run {
            let name = p.file.file_name().unwrap_or_default();
            if let Err(e) = dir.remove(name) {
                if e.kind() != std::io::ErrorKind::NotFound {
                    report.failed.push((p.file.clone(), e.kind()));
                    continue;
                }
            }
        }
        report.removed.push(p);
    }
    Ok(report)
}

fn pruned(e: &Found, reason: StaleReason) -> Pruned {
    let h = e.header.as_ref().ok();
    Pruned {
        file: e.file.clone(),
        bytes: e.bytes,
        reason,
        source: h
            .filter(|h| !h.source.is_empty())
            .map(|h| PathBuf::from(&h.source)),
        deflection: h.map(|h| f64::from_bits(h.key.linear)),
    }
}

/// The stored files of a store (for tests and tools).
#[allow(dead_code)]
pub(crate) fn stored_files(store: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(store)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "tess"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[cfg(test)]
mod tests;
