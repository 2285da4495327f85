//! [`Trajectory`]: time-stamped samples of joint values and TCP pose, with CSV output.

use super::JointKind;
use crate::math::{AngleConvention, Transform};
use std::io::{self, Write};

/// One sample of a motion.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectorySample {
    /// Time from the start of the trajectory (s).
    pub t: f64,
    /// Joint values in joint order (rad, or mm for prismatic joints).
    pub joints: Vec<f64>,
    /// World pose of the TCP (mm).
    pub tcp: Transform,
}

/// A sampled motion: samples in time order, the first at `t = 0`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    /// The samples.
    pub samples: Vec<TrajectorySample>,
    /// Kind of each joint (decides degrees or mm in the CSV).
    pub joint_kinds: Vec<JointKind>,
}

impl Trajectory {
    /// An empty trajectory for joints of the given kinds.
    pub fn new(joint_kinds: Vec<JointKind>) -> Self {
        Self {
            samples: Vec::new(),
            joint_kinds,
        }
    }

    /// Total duration (s); 0 when empty.
    pub fn duration(&self) -> f64 {
        self.samples.last().map_or(0.0, |s| s.t)
    }

    /// Joint values at the end, if any sample.
    pub fn last_joints(&self) -> Option<&[f64]> {
        self.samples.last().map(|s| s.joints.as_slice())
    }

    /// Appends `other` after this trajectory (its times shifted by this duration); its
    /// first sample is dropped when it repeats this trajectory's last one.
    pub fn append(&mut self, other: Trajectory) {
        let t0 = self.duration();
        let skip_first = match (self.samples.last(), other.samples.first()) {
            (Some(a), Some(b)) => b.t == 0.0 && a.joints == b.joints,
            _ => false,
        };
        if self.joint_kinds.is_empty() {
            self.joint_kinds = other.joint_kinds.clone();
        }
        for (i, mut s) in other.samples.into_iter().enumerate() {
            if i == 0 && skip_first {
                continue;
            }
            s.t += t0;
            self.samples.push(s);
        }
    }

    /// Writes the samples as CSV: header `t_s,j1_deg,…,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg`
    /// (`jN_mm` for prismatic joints), TCP angles in `conv`.
    pub fn write_csv<W: Write>(&self, mut out: W, conv: AngleConvention) -> io::Result<()> {
        let mut header = String::from("t_s");
        for (i, k) in self.joint_kinds.iter().enumerate() {
            let unit = if *k == JointKind::Prismatic {
                "mm"
            } else {
                "deg"
            };
            header.push_str(&format!(",j{}_{unit}", i + 1));
        }
        header.push_str(",x_mm,y_mm,z_mm,a_deg,b_deg,c_deg");
        writeln!(out, "{header}")?;
        for s in &self.samples {
            let mut line = format!("{:.6}", s.t);
            for (i, v) in s.joints.iter().enumerate() {
                let v = if self.joint_kinds.get(i) == Some(&JointKind::Prismatic) {
                    *v
                } else {
                    v.to_degrees()
                };
                line.push_str(&format!(",{v:.6}"));
            }
            let p = s.tcp.to_xyzabc_deg(conv);
            line.push_str(&format!(
                ",{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
                p[0], p[1], p[2], p[3], p[4], p[5]
            ));
            writeln!(out, "{line}")?;
        }
        Ok(())
    }

    /// The CSV text (see [`Trajectory::write_csv`]).
    pub fn to_csv(&self, conv: AngleConvention) -> String {
        let mut buf = Vec::new();
        // Writing to a Vec cannot fail.
        let _ = self.write_csv(&mut buf, conv);
        String::from_utf8_lossy(&buf).into_owned()
    }
}
