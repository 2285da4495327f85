//! [`Dir`]: a folder held open, and every file operation relative to it without
//! following a symbolic link — the jail's one mechanism.
//!
//! A check by name followed by a use by name can be raced: a folder swapped for a
//! symbolic link between the two sends the use outside. Here the check and the use go
//! through the same opened handle: a folder is reached by walking from a held
//! directory handle one component at a time with `openat(O_NOFOLLOW | O_DIRECTORY)`,
//! a file is opened with `openat(O_NOFOLLOW)` and checked with `fstat` on the open
//! handle, an atomic write creates its temporary file and renames it inside the held
//! folder (`openat(O_CREAT | O_EXCL | O_NOFOLLOW)`, `renameat`). A link met anywhere
//! is refused ([`std::io::ErrorKind::Other`] with "symbolic link" in its message), never
//! followed. (Non-Unix builds fall back to the same operations by path.)

use std::ffi::OsStr;
use std::io::{Read, Write};
use std::path::{Component, Path, PathBuf};

/// The error of a walk that met a symbolic link (or something that is not a folder)
/// where a folder was expected.
pub(crate) fn link_refused(at: &Path) -> std::io::Error {
    std::io::Error::other(format!(
        "{}: a symbolic link (or not a folder) where a folder was expected: not followed",
        at.display()
    ))
}

/// What [`Dir::stat`] says about a name in the folder (the name itself, never what a
/// link points to).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A regular file of this many bytes.
    File(u64),
    /// A folder.
    Dir,
    /// A symbolic link.
    Symlink,
    /// A FIFO, device or socket (its name for messages).
    Special(&'static str),
}

/// A folder held open. Operations name entries of this folder (one component), or
/// walk below it component by component; none follows a symbolic link.
#[derive(Debug)]
pub struct Dir {
    #[cfg(unix)]
    fd: std::os::fd::OwnedFd,
    /// The folder's path when it was opened (for messages, and the non-Unix fallback).
    path: PathBuf,
}

#[cfg(unix)]
mod sys {
    pub(super) use rustix::fs::{AtFlags, Mode, OFlags};
    pub(super) const DIR_FLAGS: OFlags = OFlags::RDONLY
        .union(OFlags::DIRECTORY)
        .union(OFlags::NOFOLLOW)
        .union(OFlags::CLOEXEC);
}

impl Dir {
    /// Opens the folder at `path` (following links in `path`: the caller named it).
    pub fn open(path: &Path) -> std::io::Result<Dir> {
        #[cfg(unix)]
        {
            let fd = rustix::fs::open(
                path,
                sys::OFlags::RDONLY | sys::OFlags::DIRECTORY | sys::OFlags::CLOEXEC,
                sys::Mode::empty(),
            )?;
            Ok(Dir {
                fd,
                path: path.to_path_buf(),
            })
        }
        #[cfg(not(unix))]
        {
            if !std::fs::metadata(path)?.is_dir() {
                return Err(std::io::Error::other("not a folder"));
            }
            Ok(Dir {
                path: path.to_path_buf(),
            })
        }
    }

    /// The folder's path when it was opened.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The raw descriptor of the held folder (for `/proc/self/fd/N` names handed to a
    /// library that opens by name); `None` off Unix.
    pub(crate) fn raw_fd(&self) -> Option<i32> {
        #[cfg(unix)]
        {
            use std::os::fd::AsRawFd;
            Some(self.fd.as_raw_fd())
        }
        #[cfg(not(unix))]
        {
            None
        }
    }

    /// The folder `rel` below this one (relative, plain names only: no `..`, no root),
    /// reached one component at a time without following a link; with `create`,
    /// missing folders are made (`mkdirat`, 0755 less the umask).
    pub fn walk(&self, rel: &Path, create: bool) -> std::io::Result<Dir> {
        let mut names = Vec::new();
        for c in rel.components() {
            match c {
                Component::Normal(n) => names.push(n),
                Component::CurDir => {}
                _ => {
                    return Err(std::io::Error::other(format!(
                        "{}: only plain folder names are walked (no `..` or root)",
                        rel.display()
                    )))
                }
            }
        }
        #[cfg(unix)]
        {
            let mut path = self.path.clone();
            let mut fd = rustix::io::dup(&self.fd)?;
            for n in names {
                path.push(n);
                let next = match rustix::fs::openat(&fd, n, sys::DIR_FLAGS, sys::Mode::empty()) {
                    Err(rustix::io::Errno::NOENT) if create => {
                        match rustix::fs::mkdirat(&fd, n, sys::Mode::from_raw_mode(0o755)) {
                            Ok(()) | Err(rustix::io::Errno::EXIST) => {}
                            Err(e) => return Err(e.into()),
                        }
                        rustix::fs::openat(&fd, n, sys::DIR_FLAGS, sys::Mode::empty())
                    }
                    other => other,
                };
                fd = match next {
                    Ok(f) => f,
                    Err(rustix::io::Errno::LOOP | rustix::io::Errno::NOTDIR) => {
                        return Err(link_refused(&path))
                    }
                    Err(e) => return Err(e.into()),
                };
            }
            Ok(Dir { fd, path })
        }
        #[cfg(not(unix))]
        {
            let mut path = self.path.clone();
            for n in names {
                path.push(n);
                match std::fs::symlink_metadata(&path) {
                    Ok(m) if m.is_dir() => {}
                    Ok(_) => return Err(link_refused(&path)),
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound && create => {
                        std::fs::create_dir(&path)?
                    }
                    Err(e) => return Err(e),
                }
            }
            Ok(Dir { path })
        }
    }

    /// What `name` is in this folder, without following it (`None`: nothing there).
    pub(crate) fn stat(&self, name: &OsStr) -> std::io::Result<Option<Kind>> {
        #[cfg(unix)]
        {
            use rustix::fs::FileType as T;
            let st = match rustix::fs::statat(&self.fd, name, sys::AtFlags::SYMLINK_NOFOLLOW) {
                Ok(st) => st,
                Err(rustix::io::Errno::NOENT) => return Ok(None),
                Err(e) => return Err(e.into()),
            };
            Ok(Some(match T::from_raw_mode(st.st_mode) {
                T::RegularFile => Kind::File(st.st_size as u64),
                T::Directory => Kind::Dir,
                T::Symlink => Kind::Symlink,
                T::Fifo => Kind::Special("a FIFO"),
                T::Socket => Kind::Special("a socket"),
                T::CharacterDevice | T::BlockDevice => Kind::Special("a device"),
                T::Unknown => Kind::Special("not a regular file"),
            }))
        }
        #[cfg(not(unix))]
        {
            match std::fs::symlink_metadata(self.path.join(name)) {
                Ok(m) if m.file_type().is_symlink() => Ok(Some(Kind::Symlink)),
                Ok(m) if m.is_dir() => Ok(Some(Kind::Dir)),
                Ok(m) if m.is_file() => Ok(Some(Kind::File(m.len()))),
                Ok(_) => Ok(Some(Kind::Special("not a regular file"))),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
                Err(e) => Err(e),
            }
        }
    }

    /// Opens the regular file `name` of this folder for reading: a link is refused
    /// (not followed), and a FIFO, device or socket is refused after the open
    /// (opened non-blocking, so a FIFO cannot block), by `fstat` on the handle.
    pub(crate) fn open_file(&self, name: &OsStr) -> std::io::Result<std::fs::File> {
        #[cfg(unix)]
        {
            let fd = match rustix::fs::openat(
                &self.fd,
                name,
                sys::OFlags::RDONLY
                    | sys::OFlags::NOFOLLOW
                    | sys::OFlags::NONBLOCK
                    | sys::OFlags::CLOEXEC
                    | sys::OFlags::NOCTTY,
                sys::Mode::empty(),
            ) {
                Ok(fd) => fd,
                Err(rustix::io::Errno::LOOP) => {
                    return Err(std::io::Error::other(format!(
                        "{}: a symbolic link: not followed",
                        self.path.join(name).display()
                    )))
                }
                Err(e) => return Err(e.into()),
            };
            let st = rustix::fs::fstat(&fd)?;
            let kind = rustix::fs::FileType::from_raw_mode(st.st_mode);
            if kind != rustix::fs::FileType::RegularFile {
                use rustix::fs::FileType as T;
                let what = match kind {
                    T::Directory => "a folder",
                    T::Fifo => "a FIFO",
                    T::Socket => "a socket",
                    T::CharacterDevice | T::BlockDevice => "a device",
                    _ => "not a regular file",
                };
                return Err(std::io::Error::other(format!(
                    "not a regular file (it is {what}): fitup reads only regular files"
                )));
            }
            let flags = rustix::fs::fcntl_getfl(&fd)?;
            rustix::fs::fcntl_setfl(&fd, flags - sys::OFlags::NONBLOCK)?;
            Ok(std::fs::File::from(fd))
        }
        #[cfg(not(unix))]
        {
            let p = self.path.join(name);
            if std::fs::symlink_metadata(&p)?.file_type().is_symlink() {
                return Err(std::io::Error::other("a symbolic link: not followed"));
            }
            std::fs::File::open(p)
        }
    }

    /// Opens the regular file `name` for writing in place (no truncation, no create):
    /// for marking a file used (its modification time).
    pub(crate) fn open_file_rw(&self, name: &OsStr) -> std::io::Result<std::fs::File> {
        #[cfg(unix)]
        {
            let fd = rustix::fs::openat(
                &self.fd,
                name,
                sys::OFlags::WRONLY
                    | sys::OFlags::NOFOLLOW
                    | sys::OFlags::NONBLOCK
                    | sys::OFlags::CLOEXEC
                    | sys::OFlags::NOCTTY,
                sys::Mode::empty(),
            )?;
            let st = rustix::fs::fstat(&fd)?;
            if rustix::fs::FileType::from_raw_mode(st.st_mode) != rustix::fs::FileType::RegularFile
            {
                return Err(std::io::Error::other("not a regular file"));
            }
            Ok(std::fs::File::from(fd))
        }
        #[cfg(not(unix))]
        {
            std::fs::OpenOptions::new()
                .write(true)
                .open(self.path.join(name))
        }
    }

    /// Removes the file (or link) `name` of this folder — the name itself, never what
    /// a link points to.
    pub(crate) fn remove(&self, name: &OsStr) -> std::io::Result<()> {
        #[cfg(unix)]
        {
            rustix::fs::unlinkat(&self.fd, name, sys::AtFlags::empty())?;
            Ok(())
        }
        #[cfg(not(unix))]
        {
            std::fs::remove_file(self.path.join(name))
        }
    }

    /// The names in this folder (not `.` and `..`), with what each is (not followed).
    pub(crate) fn entries(&self) -> std::io::Result<Vec<(std::ffi::OsString, Kind)>> {
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            let mut out = Vec::new();
            let dir = rustix::fs::Dir::read_from(&self.fd)?;
            for e in dir {
                let e = e?;
                let name = OsStr::from_bytes(e.file_name().to_bytes()).to_os_string();
                if name == "." || name == ".." {
                    continue;
                }
                if let Some(kind) = self.stat(&name)? {
                    out.push((name, kind));
                }
            }
            Ok(out)
        }
        #[cfg(not(unix))]
        {
            let mut out = Vec::new();
            for e in std::fs::read_dir(&self.path)? {
                let name = e?.file_name();
                if let Some(kind) = self.stat(&name)? {
                    out.push((name, kind));
                }
            }
            Ok(out)
        }
    }

    /// Takes this folder's exclusive advisory lock (released when the returned handle
    /// is dropped); `None` when the file system cannot lock.
    pub(crate) fn lock(&self) -> Option<DirLock> {
        #[cfg(unix)]
        {
            let fd = rustix::io::dup(&self.fd).ok()?;
            rustix::fs::flock(&fd, rustix::fs::FlockOperation::LockExclusive).ok()?;
            Some(DirLock { _fd: fd })
        }
        #[cfg(not(unix))]
        {
            let f = std::fs::File::open(&self.path).ok()?;
            f.lock().ok()?;
            Some(DirLock { _fd: f })
        }
    }

    /// Reads the regular file `name` whole, at most `cap` bytes (`Ok(None)`: larger).
    pub(crate) fn read_capped(&self, name: &OsStr, cap: u64) -> std::io::Result<Option<Vec<u8>>> {
        let f = self.open_file(name)?;
        let len = f.metadata()?.len();
        if len > cap {
            return Ok(None);
        }
        let mut bytes = Vec::with_capacity(len as usize);
        f.take(cap + 1).read_to_end(&mut bytes)?;
        Ok((bytes.len() as u64 <= cap).then_some(bytes))
    }

    /// Writes `bytes` as `name` in this folder atomically: a temporary
    /// `.fitup-<random>.tmp` created here (exclusively, never through a link), written,
    /// synced, given `mode` (Unix permission bits; `None`: those of the file replaced,
    /// else 0644), then renamed over `name` here. On any error the temporary file is
    /// removed; a crash may leave one (`fitup cache prune` removes old ones in the
    /// tessellation store).
    pub(crate) fn write_atomic(&self, name: &OsStr, bytes: &[u8]) -> std::io::Result<()> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = match rustix::fs::statat(&self.fd, name, sys::AtFlags::SYMLINK_NOFOLLOW) {
                Ok(st)
                    if rustix::fs::FileType::from_raw_mode(st.st_mode)
                        == rustix::fs::FileType::RegularFile =>
                {
                    st.st_mode & 0o7777
                }
                _ => 0o644,
            };
            let (tmp, fd) = self.create_temp()?;
            let result = (|| {
                let mut f = std::fs::File::from(fd);
                f.write_all(bytes)?;
                f.set_permissions(std::fs::Permissions::from_mode(mode))?;
                f.sync_all()?;
                drop(f);
                rustix::fs::renameat(&self.fd, tmp.as_str(), &self.fd, name)?;
                Ok(())
            })();
            if result.is_err() {
                let _ = rustix::fs::unlinkat(&self.fd, tmp.as_str(), sys::AtFlags::empty());
            }
            result
        }
        #[cfg(not(unix))]
        {
            super::write_atomic(&self.path.join(name), bytes)
        }
    }

    /// A new temporary file `.fitup-<random>.tmp` in this folder, created exclusively.
    #[cfg(unix)]
    fn create_temp(&self) -> std::io::Result<(String, std::os::fd::OwnedFd)> {
        let mut last = None;
        for _ in 0..16 {
            let name = format!(".fitup-{:016x}.tmp", random_u64());
            match rustix::fs::openat(
                &self.fd,
                name.as_str(),
                sys::OFlags::WRONLY
                    | sys::OFlags::CREATE
                    | sys::OFlags::EXCL
                    | sys::OFlags::NOFOLLOW
                    | sys::OFlags::CLOEXEC,
                sys::Mode::from_raw_mode(0o600),
            ) {
                Ok(fd) => return Ok((name, fd)),
                Err(rustix::io::Errno::EXIST) => last = Some(rustix::io::Errno::EXIST),
                Err(e) => return Err(e.into()),
            }
        }
        Err(last.unwrap_or(rustix::io::Errno::EXIST).into())
    }
}

/// A held folder lock ([`Dir::lock`]).
pub(crate) struct DirLock {
    #[cfg(unix)]
    _fd: std::os::fd::OwnedFd,
    #[cfg(not(unix))]
    _fd: std::fs::File,
}

/// A random number for temporary names (std's per-process random hash keys, mixed with
/// a counter so that two names in one process differ).
fn random_u64() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    h.write_u32(std::process::id());
    h.finish()
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn walks_and_opens_refuse_links() {
        let dir = tempfile::tempdir().unwrap();
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("secret.txt"), "s").unwrap();
        let d = Dir::open(dir.path()).unwrap();
        let sub = d.walk(Path::new("a/b"), true).unwrap();
        sub.write_atomic(OsStr::new("x.csv"), b"1\n").unwrap();
        assert_eq!(std::fs::read(dir.path().join("a/b/x.csv")).unwrap(), b"1\n");
        // Nothing left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path().join("a/b")).unwrap().collect();
        assert_eq!(names.len(), 1);
        std::os::unix::fs::symlink(outside.path(), dir.path().join("out")).unwrap();
        let e = d.walk(Path::new("out"), true).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        std::os::unix::fs::symlink(outside.path().join("secret.txt"), dir.path().join("s.txt"))
            .unwrap();
        let e = d.open_file(OsStr::new("s.txt")).unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert_eq!(d.stat(OsStr::new("s.txt")).unwrap(), Some(Kind::Symlink));
        assert!(d.walk(Path::new("../x"), false).is_err());
        // A write over a link replaces the link, never the file it points to.
        d.write_atomic(OsStr::new("s.txt"), b"mine").unwrap();
        assert_eq!(
            std::fs::read(outside.path().join("secret.txt")).unwrap(),
            b"s"
        );
    }
}
