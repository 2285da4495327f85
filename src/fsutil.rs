//! File-system helpers shared by every reader and writer: atomic writes, capped reads
//! of regular files, content hashes and file stamps, the held folder ([`Dir`]). The rule
//! on what an output may replace, and the registry of what fitup wrote, sit one floor
//! up, beside the project ([`crate::project::check_output`]).

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

/// `p` absolute with its links and `..` resolved; for a file that does not exist yet,
/// its folder resolved and its name: the form in which two paths naming the same file
/// compare equal.
pub(crate) fn resolved_path(p: &Path) -> std::path::PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    match (
        abs.parent().and_then(|d| d.canonicalize().ok()),
        abs.file_name(),
    ) {
        (Some(d), Some(n)) => d.join(n),
        _ => abs,
    }
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

/// The first `n` bytes of a file (fewer when it is shorter).
pub(crate) fn file_head(path: &Path, n: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path)?.take(n).read_to_end(&mut head)?;
    Ok(head)
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
