//! File-system helpers shared by every writer: atomic writes, the one rule on what an
//! output may replace ([`check_output`]), capped reads of regular files.

mod jail;

pub use jail::Dir;
pub(crate) use jail::Kind;
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed
/// and synced, then renamed over the target. A crash or error leaves the old file
/// untouched; a reader never sees a half-written file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".fitup-")
        .suffix(".tmp")
        .tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    // Keep the permissions of the file being replaced; new files get the usual 0644
    // rather than the temporary file's private 0600.
    let perms = match std::fs::metadata(path) {
        Ok(md) => md.permissions(),
        Err(_) => {
            #[cfg(unix)]
            {
                std::os::unix::fs::PermissionsExt::from_mode(0o644)
            }
            #[cfg(not(unix))]
            {
                tmp.as_file().metadata()?.permissions()
            }
        }
    };
    tmp.as_file().set_permissions(perms)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// A 64-bit hash of file contents (FNV-1a), used to tell a real change from a save
/// that wrote the same bytes.
pub fn content_hash(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Length, modification time and (on Unix) inode of a file: the cheap first test of
/// "changed?". The inode matters because editors and [`write_atomic`] replace files by
/// rename, and two saves within the file system's timestamp granularity would
/// otherwise look the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stamp {
    len: u64,
    modified: std::time::SystemTime,
    inode: u64,
}

/// The [`Stamp`] of the file at `path`.
pub fn stamp(path: &Path) -> std::io::Result<Stamp> {
    let md = std::fs::metadata(path)?;
    #[cfg(unix)]
    let inode = std::os::unix::fs::MetadataExt::ino(&md);
    #[cfg(not(unix))]
    let inode = 0;
    Ok(Stamp {
        len: md.len(),
        modified: md.modified()?,
        inode,
    })
}

/// Takes an exclusive advisory lock on a folder (released when the returned handle is
/// dropped, or when the process dies), so that writers of files in it take turns.
/// `None` when the platform or file system cannot lock: writing goes on unlocked.
pub fn lock_folder(dir: &Path) -> Option<std::fs::File> {
    let f = std::fs::File::open(dir).ok()?;
    f.lock().ok()?;
    Some(f)
}

/// What kind of file a reader expects: each kind has its own size cap, stated in the
/// error when a file exceeds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// An assembly document (YAML).
    Document,
    /// An STL mesh.
    Mesh,
    /// A Rhai script or imported module.
    Script,
    /// A robot motion program.
    Program,
    /// A CSV table (hole tables, …).
    Table,
    /// A STEP file (ISO 10303-21), read by Open CASCADE (feature `step`).
    Step,
}

impl FileKind {
    /// The largest file of this kind fitup reads, in bytes: far above any real file of
    /// the kind, low enough that a mistaken path cannot exhaust memory.
    pub const fn max_bytes(self) -> u64 {
        match self {
            FileKind::Document => 16 << 20,
            FileKind::Mesh => 256 << 20,
            FileKind::Script => 4 << 20,
            FileKind::Program | FileKind::Table => 64 << 20,
            // Open CASCADE holds a STEP model in ≈ 10–30 times the file's size; the
            // cap keeps one import within a few GB (docs/performance.md).
            FileKind::Step => 64 << 20,
        }
    }

    /// How messages call this kind of file.
    pub const fn name(self) -> &'static str {
        match self {
            FileKind::Document => "a document",
            FileKind::Mesh => "a mesh",
            FileKind::Script => "a script",
            FileKind::Program => "a robot program",
            FileKind::Table => "a CSV table",
            FileKind::Step => "a STEP file",
        }
    }
}

/// An operating-system error kept shareable (the errors that carry one are `Clone`);
/// two compare equal when their kinds and messages do.
#[derive(Debug, Clone, thiserror::Error)]
#[error(transparent)]
pub struct IoCause(std::sync::Arc<std::io::Error>);

impl IoCause {
    /// The kind of the operating system's error.
    pub fn kind(&self) -> std::io::ErrorKind {
        self.0.kind()
    }
}

impl From<std::io::Error> for IoCause {
    fn from(e: std::io::Error) -> Self {
        IoCause(std::sync::Arc::new(e))
    }
}

impl PartialEq for IoCause {
    fn eq(&self, other: &Self) -> bool {
        self.0.kind() == other.0.kind() && self.0.to_string() == other.0.to_string()
    }
}

impl Eq for IoCause {}

/// Why a file could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ReadError {
    /// The operating system refused (missing file, permissions, …).
    #[error("cannot read: {0}")]
    Io(#[source] IoCause),
    /// A path inside the project whose folder cannot be resolved.
    #[error("cannot read: {}: cannot resolve its folder", .0.display())]
    FolderUnresolvable(std::path::PathBuf),
    /// A path inside the project as written that a symbolic link on the way leads out
    /// of it.
    #[error("cannot read: {}: a symbolic link on the way leads outside the project folder {}: not followed", .path.display(), .root.display())]
    LinkOutside {
        /// The path as given.
        path: std::path::PathBuf,
        /// The project folder.
        root: std::path::PathBuf,
    },
    /// A folder, device, FIFO or socket: only regular files are read, because reading
    /// `/dev/zero` never ends and opening a FIFO waits for a writer forever.
    #[error("not a regular file (it is {0}): fitup reads only regular files")]
    NotRegular(&'static str),
    /// Larger than the cap of its kind.
    #[error("{size} bytes is larger than the {cap} MiB limit for {what}")]
    TooLarge {
        /// The file size in bytes.
        size: u64,
        /// The cap in MiB.
        cap: u64,
        /// The kind of file.
        what: &'static str,
    },
    /// Not UTF-8 text where text was expected.
    #[error("not UTF-8 text (byte {0})")]
    NotText(usize),
}

pub(crate) fn file_type_name(md: &std::fs::Metadata) -> &'static str {
    let t = md.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a folder"
    } else {
        "not a regular file"
    }
}

/// Reads a regular file of `kind`, refusing folders, devices and FIFOs (checked before
/// the file is opened, so a FIFO cannot block) and files over [`FileKind::max_bytes`].
/// The read itself is bounded too, in case the file grows while it is read.
pub fn read_file(path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError> {
    let cap = kind.max_bytes();
    let too_large = |size| ReadError::TooLarge {
        size,
        cap: cap >> 20,
        what: kind.name(),
    };
    let md = std::fs::metadata(path).map_err(|e| ReadError::Io(e.into()))?;
    if !md.is_file() {
        return Err(ReadError::NotRegular(file_type_name(&md)));
    }
    if md.len() > cap {
        return Err(too_large(md.len()));
    }
    let file = std::fs::File::open(path).map_err(|e| ReadError::Io(e.into()))?;
    // The path may have been replaced between the check and the open.
    read_opened(file, kind)
}

/// Reads an opened file of `kind` whole: refused when the handle is not a regular file
/// or holds more than [`FileKind::max_bytes`] (checked on the handle, and the read is
/// bounded too, in case the file grows while it is read).
pub fn read_opened(file: std::fs::File, kind: FileKind) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let cap = kind.max_bytes();
    let too_large = |size| ReadError::TooLarge {
        size,
        cap: cap >> 20,
        what: kind.name(),
    };
    let md = file.metadata().map_err(|e| ReadError::Io(e.into()))?;
    if !md.is_file() {
        return Err(ReadError::NotRegular(file_type_name(&md)));
    }
    if md.len() > cap {
        return Err(too_large(md.len()));
    }
    let mut bytes = Vec::with_capacity(md.len().min(cap) as usize);
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| ReadError::Io(e.into()))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// [`read_file`] for text files: the bytes must be UTF-8.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String, ReadError> {
    String::from_utf8(read_file(path, kind)?)
        .map_err(|e| ReadError::NotText(e.utf8_error().valid_up_to()))
}

/// The file, in every folder fitup writes outputs to, that lists the outputs it wrote
/// there (name, size, content hash): the proof that a file is fitup's own, see
/// [`check_output`].
pub const OUTPUT_REGISTRY: &str = ".fitup-outputs";

/// The first line of [`OUTPUT_REGISTRY`] (a reader refuses a file without it).
const REGISTRY_HEADER: &str = "# fitup output registry v1: files fitup wrote in this folder (size, content hash, name); fitup may replace a file listed here while its contents are unchanged. Delete this file to forget them.";

/// The largest registry read; past it the oldest entries are dropped when a new one is
/// added, so the file stays bounded (about 20,000 entries).
const REGISTRY_MAX_BYTES: usize = 1 << 20;

/// The first bytes of a SQLite database file.
pub const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// The first bytes of a Rerun recording (`.rrd`), which `--record` streams.
pub const RRD_MAGIC: &[u8; 4] = b"RRF2";

/// Extensions of the files that hold the user's work (documents, meshes, scripts,
/// programs, robot descriptions, the project file): never replaced by an output
/// without `--force`, whoever wrote them.
const PROJECT_EXTENSIONS: &[&str] = &[
    "yaml", "yml", "stl", "obj", "ply", "gltf", "rhai", "prg", "toml", "urdf", "xacro", "dae",
    "sdf", "step", "stp",
];
// `.glb` is not listed: `fitup export` writes it and replaces its own output; a GLB the
// user made is still refused (not in the registry), and one the run read as a part mesh
// is refused through `OutputRule::used`.

/// How a writer may treat an existing file at its output path (see [`check_output`]).
#[derive(Clone, Copy, Default)]
pub struct OutputRule<'a> {
    /// `--force` on the command line, `overwrite: true` in a script: replace any
    /// regular file (never a folder, FIFO, device or symbolic link).
    pub force: bool,
    /// The files the project uses that are not known by their extension: the files
    /// this run read (documents, meshes, URDFs, hole tables, problem files, imported
    /// scripts). `None`: no run (the CLI's own writers).
    pub used: Option<&'a (dyn Fn(&Path) -> bool + Sync)>,
    /// How this writer's output always begins (the API reference's title and
    /// "Generated by `fitup docs`" line): a file that begins so is fitup's own even
    /// when the registry does not list it (a fresh clone of a repository).
    pub signature: Option<&'a [u8]>,
}

impl std::fmt::Debug for OutputRule<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OutputRule")
            .field("force", &self.force)
            .field("used", &self.used.is_some())
            .field("signature", &self.signature.map(String::from_utf8_lossy))
            .finish()
    }
}

impl<'a> OutputRule<'a> {
    /// The rule with `force` (`--force` / `overwrite: true`) and no run's files.
    pub fn forced(force: bool) -> Self {
        Self {
            force,
            used: None,
            signature: None,
        }
    }
}

/// Why a writer refused to write its output (nothing was written).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// A folder, FIFO, device or socket is at the path.
    #[error("refusing to write over {0}: outputs replace only regular files")]
    NotRegular(&'static str),
    /// A symbolic link is at the path: writing would replace the link or the file it
    /// points to, and neither is clearly meant.
    #[error("refusing to write over a symbolic link: name the file it points to, or a new file")]
    Symlink,
    /// fitup's own bookkeeping (the registry, a temporary file of an atomic write).
    #[error("refusing to write over fitup's own bookkeeping file (`{OUTPUT_REGISTRY}` or a `.fitup-*.tmp` file)")]
    Bookkeeping,
    /// A file the project uses: a document, mesh, script, … or a file the run read.
    #[error("refusing to overwrite {what}, a file the project uses; write to another file, or replace it on purpose with `overwrite: true` (a script's option) or `--force` (command line)")]
    InUse {
        /// What the file is ("a results database (SQLite)", "a file this run read", …).
        what: &'static str,
    },
    /// An existing file fitup did not write (not in the folder's registry with its
    /// current contents).
    #[error("refusing to overwrite a file fitup did not write (it is not listed in {OUTPUT_REGISTRY} of its folder with its current contents); write to another file, or replace it on purpose with `overwrite: true` (a script's option) or `--force` (command line)")]
    NotOurs,
    /// The operating system refused (permissions, a full disk, …).
    #[error("cannot write: {0}")]
    Io(#[source] IoCause),
    /// The path ends in `..` or is a root: no file name.
    #[error("cannot write: {}: not a file name", .0.display())]
    NotAFileName(std::path::PathBuf),
}

fn io_err(e: std::io::Error) -> OutputError {
    OutputError::Io(e.into())
}

/// The one rule for every file a run writes (CSV logs and exports, plans, key poses,
/// recordings, the API reference, the demo project); see "What a run writes" in
/// docs/scripting.md. An existing `path` may be replaced only when
///
/// 1. it is a regular file, not a symbolic link, and not fitup's bookkeeping
///    ([`OUTPUT_REGISTRY`], `.fitup-*.tmp`) — these hold even with `force`;
/// 2. with `force`, any such file; otherwise
/// 3. it is not a file the project uses: no project extension (`yaml`, `yml`, `stl`,
///    `obj`, `ply`, `gltf`, `rhai`, `prg`, `toml`, `urdf`, `xacro`, `dae`, `sdf`, `step`, `stp`), not a SQLite
///    database (by its first 16 bytes, whatever its name), not a file the run read
///    ([`OutputRule::used`]); and
/// 4. fitup wrote it: the registry of its folder lists its name with its current size
///    and content hash ([`register_output`]), or, for a streamed recording, its name
///    as a stream and the file starts with that stream's magic ([`register_stream`]),
///    or the file begins with the writer's [`OutputRule::signature`].
///
/// A file that does not exist may always be written. Checked before anything is
/// written; nothing is changed here.
pub fn check_output(path: &Path, rule: &OutputRule) -> Result<(), OutputError> {
    // A folder that does not exist yet holds nothing to replace.
    if path
        .parent()
        .is_some_and(|d| !d.as_os_str().is_empty() && std::fs::symlink_metadata(d).is_err())
    {
        return Ok(());
    }
    let (dir, name) = open_parent(path)?;
    check_output_in(&dir, &name, path, rule)
}

/// The folder of `path` held open, and the file's name in it: what a writer checks
/// and writes through, so that the check and the write see the same folder.
fn open_parent(path: &Path) -> Result<(Dir, std::ffi::OsString), OutputError> {
    let name = path
        .file_name()
        .ok_or_else(|| OutputError::NotAFileName(path.to_path_buf()))?
        .to_os_string();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Ok((Dir::open(dir).map_err(io_err)?, name))
}

/// [`check_output`] for the file `name` of the held folder `dir` (`path`, its full
/// path, for [`OutputRule::used`]): every look at the file and at the registry goes
/// through `dir`, never through a link.
pub(crate) fn check_output_in(
    dir: &Dir,
    name: &std::ffi::OsStr,
    path: &Path,
    rule: &OutputRule,
) -> Result<(), OutputError> {
    let text_name = name.to_str().unwrap_or("");
    if text_name == OUTPUT_REGISTRY
        || (text_name.starts_with(".fitup-") && text_name.ends_with(".tmp"))
    {
        return Err(OutputError::Bookkeeping);
    }
    let len = match dir.stat(name).map_err(io_err)? {
        None => return Ok(()),
        Some(Kind::Symlink) => return Err(OutputError::Symlink),
        Some(Kind::Dir) => return Err(OutputError::NotRegular("a folder")),
        Some(Kind::Special(what)) => return Err(OutputError::NotRegular(what)),
        Some(Kind::File(len)) => len,
    };
    if rule.force {
        return Ok(());
    }
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if PROJECT_EXTENSIONS.contains(&ext.as_str()) {
        return Err(OutputError::InUse {
            what: "a document, mesh, script, program, robot description or project file",
        });
    }
    let sig_len = rule.signature.map_or(0, <[u8]>::len) as u64;
    let head = {
        use std::io::Read;
        let mut head = Vec::new();
        dir.open_file(name)
            .and_then(|f| f.take(sig_len.max(16)).read_to_end(&mut head))
            .map_err(io_err)?;
        head
    };
    if head.starts_with(SQLITE_MAGIC) {
        return Err(OutputError::InUse {
            what: "a SQLite database (a results database)",
        });
    }
    if rule.used.is_some_and(|used| used(path)) {
        return Err(OutputError::InUse {
            what: "a file this run read (a document, mesh, URDF, table, problem or script)",
        });
    }
    if rule
        .signature
        .is_some_and(|sig| !sig.is_empty() && head.starts_with(sig))
    {
        return Ok(());
    }
    match registered(dir, text_name, len, &head) {
        Ok(true) => Ok(()),
        Ok(false) => Err(OutputError::NotOurs),
        Err(e) => Err(io_err(e)),
    }
}

/// [`check_output`], then [`write_atomic`], then [`register_output`]: how every
/// writer of a whole file writes its output. The folder is opened once; the check,
/// the temporary file, the rename and the registry all go through that handle.
pub fn write_output(path: &Path, bytes: &[u8], rule: &OutputRule) -> Result<(), OutputError> {
    let (dir, name) = open_parent(path)?;
    check_output_in(&dir, &name, path, rule)?;
    write_in(&dir, &name, bytes)
}

/// The second half of [`write_output`] for a path that already passed
/// [`check_output`]: [`write_atomic`], then the registry entry. A project's writers
/// use [`crate::project::Project::write_output`], which checks and writes through one
/// handle walked from the project root.
pub fn write_checked(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let (dir, name) = open_parent(path)?;
    write_in(&dir, &name, bytes)
}

/// Writes `bytes` as `name` in the held folder `dir` atomically, then lists it in the
/// folder's registry.
pub(crate) fn write_in(dir: &Dir, name: &std::ffi::OsStr, bytes: &[u8]) -> Result<(), OutputError> {
    dir.write_atomic(name, bytes).map_err(io_err)?;
    // The output is written; a registry that cannot be updated (a read-only folder
    // entry, a full disk) only means a later write there needs --force.
    let _ = register(
        dir,
        name,
        Entry::File {
            len: bytes.len() as u64,
            hash: content_hash(bytes),
        },
    );
    Ok(())
}

/// Lists the file at `path` (as it is now) in its folder's [`OUTPUT_REGISTRY`], so a
/// later [`check_output`] knows fitup wrote it. For writers that produce the file
/// themselves (after [`check_output`]).
pub fn register_output(path: &Path) -> std::io::Result<()> {
    let (dir, name) = open_parent(path).map_err(std::io::Error::other)?;
    let (len, hash) = hash_file(&dir, &name)?;
    register(&dir, &name, Entry::File { len, hash })
}

/// Lists `path` in its folder's [`OUTPUT_REGISTRY`] as a file fitup streams (a `.rrd`
/// recording, written while the run goes on, so its final contents are not known):
/// [`check_output`] accepts the file while it starts with `magic`.
pub fn register_stream(path: &Path, magic: &[u8]) -> std::io::Result<()> {
    let (dir, name) = open_parent(path).map_err(std::io::Error::other)?;
    register(&dir, &name, Entry::Stream(magic.to_vec()))
}

/// The first `n` bytes of a file (fewer when it is shorter).
pub(crate) fn file_head(path: &Path, n: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path)?.take(n).read_to_end(&mut head)?;
    Ok(head)
}

/// Size and [`content_hash`] of the file `name` of `dir`, read in chunks (outputs can
/// be large), never through a link.
fn hash_file(dir: &Dir, name: &std::ffi::OsStr) -> std::io::Result<(u64, u64)> {
    hash_reader(dir.open_file(name)?)
}

/// Size and [`content_hash`] of what `r` reads, in chunks.
pub(crate) fn hash_reader(mut r: impl std::io::Read) -> std::io::Result<(u64, u64)> {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut len = 0u64;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = r.read(&mut buf)?;
        if n == 0 {
            break;
        }
        for &b in &buf[..n] {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        len += n as u64;
    }
    Ok((len, h))
}

/// One registry line's claim about a file.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Entry {
    /// A whole file fitup wrote, by size and content hash.
    File { len: u64, hash: u64 },
    /// A file fitup streams, by its leading magic bytes (hex in the file).
    Stream(Vec<u8>),
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(s: &str) -> Option<Vec<u8>> {
    if !s.len().is_multiple_of(2) || s.len() > 64 {
        return None;
    }
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(s.get(i..i + 2)?, 16).ok())
        .collect()
}

/// The registry's entries, in file order (later lines win). A missing, foreign,
/// oversized or unreadable registry (or a link in its place) lists nothing: the safe
/// reading.
fn read_registry(dir: &Dir) -> Vec<(String, Entry)> {
    let Ok(Some(bytes)) = dir.read_capped(
        std::ffi::OsStr::new(OUTPUT_REGISTRY),
        2 * REGISTRY_MAX_BYTES as u64,
    ) else {
        return Vec::new();
    };
    let Ok(text) = String::from_utf8(bytes) else {
        return Vec::new();
    };
    let mut lines = text.lines();
    if lines.next() != Some(REGISTRY_HEADER) {
        return Vec::new();
    }
    lines
        .filter_map(|l| {
            let mut f = l.splitn(4, ' ');
            let (kind, a, b, name) = (f.next()?, f.next()?, f.next()?, f.next()?);
            let entry = match kind {
                "file" => Entry::File {
                    len: a.parse().ok()?,
                    hash: u64::from_str_radix(b, 16).ok()?,
                },
                "stream" if b == "-" => Entry::Stream(unhex(a)?),
                _ => return None,
            };
            Some((name.to_string(), entry))
        })
        .collect()
}

/// Whether the registry of `dir` says fitup wrote its file `name` as it is now.
fn registered(dir: &Dir, name: &str, len: u64, head: &[u8]) -> std::io::Result<bool> {
    let entries = read_registry(dir);
    let Some((_, entry)) = entries.iter().rev().find(|(n, _)| n == name) else {
        return Ok(false);
    };
    Ok(match entry {
        Entry::Stream(magic) => !magic.is_empty() && head.starts_with(magic),
        Entry::File { len: l, hash } => {
            *l == len && {
                let (len_now, hash_now) = hash_file(dir, std::ffi::OsStr::new(name))?;
                len_now == *l && hash_now == *hash
            }
        }
    })
}

/// Adds (or replaces) the entry of `name` in the registry of `dir`, atomically and
/// under the folder's lock (parallel runs of `fitup batch` write in the same folder).
fn register(dir: &Dir, name: &std::ffi::OsStr, entry: Entry) -> std::io::Result<()> {
    let Some(name) = name.to_str() else {
        return Ok(()); // Not listed: a later write needs --force.
    };
    if name.contains(['\n', '\r']) {
        return Ok(());
    }
    let _lock = dir.lock();
    let mut entries: Vec<(String, Entry)> = read_registry(dir)
        .into_iter()
        .filter(|(n, _)| n != name && dir.stat(std::ffi::OsStr::new(n)).is_ok_and(|k| k.is_some()))
        .collect();
    entries.push((name.to_string(), entry));
    let line = |(n, e): &(String, Entry)| match e {
        Entry::File { len, hash } => format!("file {len} {hash:016x} {n}\n"),
        Entry::Stream(m) => format!("stream {} - {n}\n", hex(m)),
    };
    let mut lines: Vec<String> = entries.iter().map(line).collect();
    // Bounded: the oldest entries go first.
    let mut total: usize = lines.iter().map(String::len).sum();
    let mut drop = 0;
    while total > REGISTRY_MAX_BYTES && drop + 1 < lines.len() {
        total -= lines[drop].len();
        drop += 1;
    }
    lines.drain(..drop);
    let mut text = String::with_capacity(total + REGISTRY_HEADER.len() + 1);
    text.push_str(REGISTRY_HEADER);
    text.push('\n');
    lines.iter().for_each(|l| text.push_str(l));
    // A registry that is not a regular file (a link planted by someone) is not
    // followed: the rename replaces the link itself, inside this folder.
    dir.write_atomic(std::ffi::OsStr::new(OUTPUT_REGISTRY), text.as_bytes())
}

/// Longest line fitup reads from a stream of commands (standard input of
/// `fitup skills run`, the terminal UI's command line), in bytes.
pub const MAX_LINE_BYTES: usize = 4096;

/// One line read by [`read_line_bounded`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BoundedLine {
    /// A line (without its end of line), at most the cap long.
    Line(String),
    /// A line longer than the cap: its first bytes were dropped along with the rest
    /// (read and discarded up to its newline, in bounded memory). `bytes` counts what
    /// was read of it.
    TooLong {
        /// Bytes of the line read (all discarded).
        bytes: u64,
    },
    /// The stream ended.
    End,
}

/// Reads one line of at most `max` bytes from `r`. A longer line (e.g. a stream of
/// gigabytes without a newline) is read to its end and discarded without being
/// kept, so memory stays within `max` bytes whatever the input. Invalid UTF-8 is
/// replaced.
///
/// # Errors
/// The stream's error.
pub fn read_line_bounded(
    r: &mut impl std::io::BufRead,
    max: usize,
) -> std::io::Result<BoundedLine> {
    let mut line: Vec<u8> = Vec::new();
    let mut too_long: Option<u64> = None;
    loop {
        let buf = match r.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if buf.is_empty() {
            return Ok(match too_long {
                Some(bytes) => BoundedLine::TooLong { bytes },
                None if line.is_empty() => BoundedLine::End,
                None => BoundedLine::Line(String::from_utf8_lossy(&line).into_owned()),
            });
        }
        let (chunk, done) = match buf.iter().position(|&b| b == b'\n') {
            Some(i) => (&buf[..i], Some(i + 1)),
            None => (buf, None),
        };
        match &mut too_long {
            Some(n) => *n += chunk.len() as u64,
            None if line.len() + chunk.len() > max => {
                too_long = Some((line.len() + chunk.len()) as u64);
                line = Vec::new();
            }
            None => line.extend_from_slice(chunk),
        }
        let used = done.unwrap_or(buf.len());
        r.consume(used);
        if done.is_some() {
            return Ok(match too_long {
                Some(bytes) => BoundedLine::TooLong { bytes },
                None => {
                    if line.last() == Some(&b'\r') {
                        line.pop();
                    }
                    BoundedLine::Line(String::from_utf8_lossy(&line).into_owned())
                }
            });
        }
    }
}

/// `target` written relative to `base` when possible (both made absolute first).
pub(crate) fn relative_path(target: &Path, base: &Path) -> Option<String> {
    use std::path::PathBuf;
    let abs = |p: &Path| std::path::absolute(p).ok();
    let (t, b) = (abs(target)?, abs(base)?);
    let (tc, bc): (Vec<_>, Vec<_>) = (t.components().collect(), b.components().collect());
    let common = tc.iter().zip(&bc).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return Some(t.to_string_lossy().into_owned());
    }
    let mut out = PathBuf::new();
    for _ in common..bc.len() {
        out.push("..");
    }
    for c in &tc[common..] {
        out.push(c);
    }
    Some(out.to_string_lossy().replace('\\', "/"))
}

#[cfg(test)]
mod tests;
