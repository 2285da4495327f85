//! Open CASCADE's own reading of a STEP file, by `tests/bench/step/occt_check.cpp` (no
//! fitup code): the file's unit, every placed solid and every placed assembly with
//! its placement. The program is `FITUP_OCCT_CHECK` when set, else compiled here once
//! per test run with the C++ compiler and Debian's OCCT that `--features step` links.

use fitup::math::{Point3, Transform};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One `solid` or `assembly` line of occt_check.
#[derive(Debug, Clone)]
pub struct Placed {
    /// Names from the root, `/`-separated.
    pub path: String,
    /// The product's name.
    pub product: String,
    /// The exact B-rep volume, mm³ (solids; 0 for assemblies).
    pub volume: f64,
    /// Rotation (row-major) and translation, mm: own frame → root, column vectors.
    pub r: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl Placed {
    /// Where the placement takes the point `p` of the own frame.
    pub fn apply(&self, p: [f64; 3]) -> Point3 {
        let v: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| self.r[i][j] * p[j]).sum::<f64>() + self.t[i])
            .collect();
        Point3::new(v[0], v[1], v[2])
    }

    /// Whether `pose` moves the own frame as this placement does (within `tol` mm at
    /// the origin and at 100 mm along each axis).
    pub fn placed_as(&self, pose: &Transform, tol: f64) -> bool {
        [
            [0.0, 0.0, 0.0],
            [100.0, 0.0, 0.0],
            [0.0, 100.0, 0.0],
            [0.0, 0.0, 100.0],
        ]
        .iter()
        .all(|p| (pose.apply(&Point3::new(p[0], p[1], p[2])) - self.apply(*p)).norm() <= tol)
    }

    /// How many levels its path has (`cart/Frame-1/plate-1`: 3).
    pub fn depth(&self) -> usize {
        self.path.split('/').count()
    }
}

/// What occt_check read.
#[derive(Debug, Clone, Default)]
pub struct Reading {
    /// The file's first length unit as Open CASCADE names it.
    pub unit: String,
    /// Placed solids, in the tree's order.
    pub solids: Vec<Placed>,
    /// Placed assemblies (the roots included), each before what it holds.
    pub assemblies: Vec<Placed>,
}

/// The occt_check program: `FITUP_OCCT_CHECK`, else compiled once into cargo's
/// `CARGO_TARGET_TMPDIR` (panics when it cannot be: the step tests run only where OCCT
/// is installed).
pub fn program() -> PathBuf {
    if let Some(p) = std::env::var_os("FITUP_OCCT_CHECK") {
        return PathBuf::from(p);
    }
    static BUILT: OnceLock<PathBuf> = OnceLock::new();
    BUILT
        .get_or_init(|| {
            // In cargo's folder for integration tests' files, rebuilt when the source
            // is newer; written under a temporary name, then renamed (test processes
            // may build it at once).
            let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
            let exe = dir.join("occt_check");
            let src = super::repo().join("tests/bench/step/occt_check.cpp");
            let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
            if modified(&exe).is_some() && modified(&exe) >= modified(&src) {
                return exe;
            }
            let tmp = dir.join(format!("occt_check.{}", std::process::id()));
            let libs = OCCT_LIBS;
            let out = std::process::Command::new(std::env::var("CXX").unwrap_or("c++".into()))
                .args(["-O0", "-std=c++17", "-w", "-I/usr/include/opencascade"])
                .arg(&src)
                .args(libs.iter().map(|l| format!("-l{l}")))
                .arg("-o")
                .arg(&tmp)
                .output()
                .expect("a C++ compiler (cxx-build needs one for --features step)");
            assert!(
                out.status.success(),
                "compiling occt_check: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            std::fs::rename(&tmp, &exe).unwrap();
            exe
        })
        .clone()
}

/// occt_check's reading of `file`.
pub fn read(check: &Path, file: &Path) -> Reading {
    let o = std::process::Command::new(check)
        .arg(file)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "occt_check {}: {}",
        file.display(),
        super::text(&o)
    );
    let text = String::from_utf8(o.stdout).unwrap();
    let mut reading = Reading::default();
    let numbers =
        |s: &str| -> Vec<f64> { s.split(' ').map(|x| x.parse::<f64>().unwrap()).collect() };
    let placed = |path: &str, product: &str, volume: f64, m: &[f64]| {
        assert_eq!(m.len(), 12, "{text}");
        Placed {
            path: path.to_string(),
            product: product.to_string(),
            volume,
            r: [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]],
            t: [m[3], m[7], m[11]],
        }
    };
    for line in text.lines() {
        let f: Vec<&str> = line.split('\t').collect();
        match f[0] {
            "unit" => reading.unit = f[1].to_string(),
            "solid" => {
                let n = numbers(f[3]);
                reading.solids.push(placed(f[1], f[2], n[0], &n[1..]));
            }
            "assembly" => {
                reading
                    .assemblies
                    .push(placed(f[1], f[2], 0.0, &numbers(f[3])));
            }
            _ => panic!("occt_check said {line:?}"),
        }
    }
    reading
}

include!("../../cpp/occt_libs.rs");
