//! Where a URDF's mesh URIs point: `package://PKG/rest` by the URDF's own folder
//! layout ([`resolve_mesh`]) or looked up by package name inside the project, as ROS
//! does with its package path ([`resolve_mesh_in`]).

use std::path::{Path, PathBuf};

/// Where a mesh URI points, for a URDF at `urdf_path`, by the URDF alone (no folder is
/// looked at): `package://PKG/rest` → `<urdf folder>/../rest` when the URDF sits in a
/// `urdf/` folder of its package (the ROS-Industrial layout), else `<urdf folder>/rest`
/// (the URDF's own package, whatever `PKG` is); `file://` and plain paths are relative
/// to the URDF's folder. [`resolve_mesh_in`] looks packages up by name first. The
/// caller still checks the path (project jail).
pub fn resolve_mesh(urdf_path: &Path, uri: &str) -> PathBuf {
    let folder = urdf_path.parent().unwrap_or(Path::new(""));
    if let Some(rest) = uri.strip_prefix("package://") {
        let rest = rest.split_once('/').map_or("", |(_, r)| r);
        return own_package(folder).join(rest);
    }
    folder.join(uri.strip_prefix("file://").unwrap_or(uri))
}

/// The package folder of a URDF in `folder`: the parent of a `urdf/` folder, else the
/// folder itself.
fn own_package(folder: &Path) -> &Path {
    if folder.file_name().is_some_and(|n| n == "urdf") {
        return folder.parent().unwrap_or(Path::new(""));
    }
    folder
}

/// How [`resolve_mesh_in`] found the folder of a `package://` URI.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PackageFound {
    /// Not a `package://` URI: relative to the URDF's folder.
    NotAPackage,
    /// A folder named as the package: the URDF's own, one on the package path, or one
    /// beside or above the URDF.
    ByName,
    /// No folder has the package's name: the URDF's own package folder (see
    /// [`resolve_mesh`]).
    OwnPackage,
}

/// Where a mesh URI points, for a URDF at `urdf_path` (absolute, inside `project`),
/// looking `package://PKG/rest` up by name as ROS does with its package path, without
/// leaving the project: the first folder named `PKG` among
/// 1. the URDF's own folder and the folders above it (its own package);
/// 2. each folder of `package_path` (absolute, inside the project): the folder itself
///    when it is named `PKG`, else its sub-folder `PKG`;
/// 3. beside or above the URDF: the sub-folder `PKG` of the URDF's folder and of each
///    folder above it, nearest first, up to the project root;
///
/// then `rest` inside it. When no folder has that name, the URDF's own package
/// ([`resolve_mesh`]'s rule), so a package folder named otherwise still loads.
/// Folders are probed from the project's held root without following a link, so the
/// search never looks outside the project. Other URIs as [`resolve_mesh`].
pub fn resolve_mesh_in(
    project: &crate::project::Project,
    urdf_path: &Path,
    uri: &str,
    package_path: &[PathBuf],
) -> (PathBuf, PackageFound) {
    let Some(rest) = uri.strip_prefix("package://") else {
        return (resolve_mesh(urdf_path, uri), PackageFound::NotAPackage);
    };
    let (pkg, rest) = rest.split_once('/').unwrap_or((rest, ""));
    let folder = urdf_path.parent().unwrap_or(Path::new(""));
    let inside = |d: &Path| d.starts_with(project.root());
    let ancestors = || folder.ancestors().take_while(|d| inside(d));
    let is_dir = |d: &Path| inside(d) && project.folder(d, false).is_ok();
    let valid = !pkg.is_empty() && pkg != "." && pkg != ".." && !pkg.contains(['/', '\\']);
    if valid {
        let own = ancestors().find(|d| d.file_name().is_some_and(|n| n == pkg));
        let on_path = || {
            package_path.iter().find_map(|r| {
                if r.file_name().is_some_and(|n| n == pkg) && is_dir(r) {
                    return Some(r.clone());
                }
                Some(r.join(pkg)).filter(|d| is_dir(d))
            })
        };
        let beside = || ancestors().map(|d| d.join(pkg)).find(|d| is_dir(d));
        if let Some(dir) = own.map(Path::to_path_buf).or_else(on_path).or_else(beside) {
            return (dir.join(rest), PackageFound::ByName);
        }
    }
    (own_package(folder).join(rest), PackageFound::OwnPackage)
}
