//! SQLite files opened through a held folder handle, never by a second lookup of
//! their folder's name.
//!
//! SQLite opens a database, its `-wal`, `-shm` and `-journal` files by path name,
//! and its default VFS first rewrites the name with every symbolic link resolved. A
//! folder checked inside the project and then swapped for a link to an outside folder
//! would send SQLite outside. Here the folder is held open ([`Dir`], walked from the
//! project root without following a link) and SQLite is given the name
//! `/proc/self/fd/<folder fd>/<file>`: the kernel resolves `/proc/self/fd/<fd>` to the
//! held folder itself (not to its name), and SQLite's unix VFS opens every file with
//! `O_NOFOLLOW`, so a link put at the file's own name is refused. The VFS used,
//! `fitup-held`, is the default unix VFS with one change: names under
//! `/proc/self/fd/` are taken as they are (the default would read the magic link
//! back into the folder's path name and open by that name again). On systems without
//! `/proc/self/fd` the folder's path is used (the race stays open there).

use crate::fsutil::Dir;
use std::ffi::{OsStr, OsString};
use std::path::PathBuf;

/// The name of the VFS registered by [`vfs`].
const VFS_NAME: &std::ffi::CStr = c"fitup-held";

/// The prefix of names the VFS takes as they are.
#[cfg(target_os = "linux")]
const FD_PREFIX: &[u8] = b"/proc/self/fd/";

/// A database file's folder held open, and the file's name in it.
#[derive(Debug)]
pub(crate) struct HeldFile {
    dir: Dir,
    name: OsString,
}

impl HeldFile {
    /// `name` in the held folder `dir`.
    pub(crate) fn new(dir: Dir, name: &OsStr) -> HeldFile {
        HeldFile {
            dir,
            name: name.to_os_string(),
        }
    }

    /// The held folder.
    pub(crate) fn dir(&self) -> &Dir {
        &self.dir
    }

    /// The file's name in the held folder.
    pub(crate) fn name(&self) -> &OsStr {
        &self.name
    }

    /// The name SQLite is given, and the VFS to give it to: `/proc/self/fd/N/name`
    /// with [`vfs`] where the system has it, else the folder's path and the default VFS.
    pub(crate) fn sqlite_name(&self) -> (PathBuf, Option<&'static str>) {
        #[cfg(target_os = "linux")]
        {
            if let (Some(fd), Some(vfs)) = (self.dir.raw_fd(), vfs()) {
                let proc = PathBuf::from(format!("/proc/self/fd/{fd}"));
                if proc.is_dir() {
                    return (proc.join(&self.name), Some(vfs));
                }
            }
        }
        (self.dir.path().join(&self.name), None)
    }
}

/// Registers the `fitup-held` VFS once (the default VFS with names under
/// `/proc/self/fd/` taken as they are); `None` when SQLite has no default VFS.
#[cfg(target_os = "linux")]
fn vfs() -> Option<&'static str> {
    use rusqlite::ffi;
    use std::sync::OnceLock;
    /// The default VFS's own `xFullPathname`, for every other name.
    static BASE: OnceLock<Option<BaseVfs>> = OnceLock::new();
    struct BaseVfs {
        vfs: *mut ffi::sqlite3_vfs,
        full_pathname: unsafe extern "C" fn(
            *mut ffi::sqlite3_vfs,
            *const std::ffi::c_char,
            std::ffi::c_int,
            *mut std::ffi::c_char,
        ) -> std::ffi::c_int,
    }
    // SAFETY: the pointer is SQLite's registered default VFS, which lives as long as
    // the process and is never written through here.
    unsafe impl Send for BaseVfs {}
    unsafe impl Sync for BaseVfs {}

    unsafe extern "C" fn full_pathname(
        _vfs: *mut ffi::sqlite3_vfs,
        name: *const std::ffi::c_char,
        n_out: std::ffi::c_int,
        out: *mut std::ffi::c_char,
    ) -> std::ffi::c_int {
        // SAFETY: SQLite passes a NUL-terminated name and an output buffer of n_out
        // bytes (its mxPathname + 1).
        unsafe {
            let bytes = std::ffi::CStr::from_ptr(name).to_bytes();
            if bytes.starts_with(FD_PREFIX) {
                let Ok(n) = usize::try_from(n_out) else {
                    return ffi::SQLITE_CANTOPEN;
                };
                if bytes.len() + 1 > n {
                    return ffi::SQLITE_CANTOPEN;
                }
                std::ptr::copy_nonoverlapping(name, out, bytes.len() + 1);
                return ffi::SQLITE_OK;
            }
            match BASE.get() {
                Some(Some(b)) => (b.full_pathname)(b.vfs, name, n_out, out),
                _ => ffi::SQLITE_CANTOPEN,
            }
        }
    }

    BASE.get_or_init(|| {
        // SAFETY: sqlite3_vfs_find and sqlite3_vfs_register are thread-safe once
        // SQLite is initialised (they initialise it); the copy of the default VFS is
        // leaked, so it outlives every connection, as registration requires.
        unsafe {
            if ffi::sqlite3_initialize() != ffi::SQLITE_OK {
                return None;
            }
            let existing = ffi::sqlite3_vfs_find(VFS_NAME.as_ptr());
            let base = ffi::sqlite3_vfs_find(std::ptr::null());
            if base.is_null() {
                return None;
            }
            let full = (*base).xFullPathname?;
            if existing.is_null() {
                let mut copy: ffi::sqlite3_vfs = *base;
                copy.pNext = std::ptr::null_mut();
                copy.zName = VFS_NAME.as_ptr();
                copy.xFullPathname = Some(full_pathname);
                let leaked = Box::into_raw(Box::new(copy));
                if ffi::sqlite3_vfs_register(leaked, 0) != ffi::SQLITE_OK {
                    drop(Box::from_raw(leaked));
                    return None;
                }
            }
            Some(BaseVfs {
                vfs: base,
                full_pathname: full,
            })
        }
    })
    .as_ref()
    .map(|_| VFS_NAME.to_str().unwrap_or("fitup-held"))
}
