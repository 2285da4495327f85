//! [`Robot`]: a kinematic tree with a base pose, a flange link, a tool (TCP) frame and
//! the ordered list of its movable joints.

use super::closed_form;
use super::{
    DescriptionProblem, IkError, IkOptions, IkSolution, JointKind, JointLimits, KinematicTree,
    KinematicsError, LinkProblem, NumericIk, OpwSolver, UrSolver,
};
use crate::math::{AngleConvention, Transform};
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion};

/// A robot arm: a [`KinematicTree`], the world pose of its root (`base`), the link that
/// carries the tool (`flange`), the tool centre point in the flange frame (`tool`),
/// and its joints: the movable links on the path from the root to the flange, in order.
///
/// Joint vectors passed to a robot have one value per joint, in that order (radians
/// for revolute joints, mm for prismatic ones). Movable links that are not on the
/// flange chain (e.g. gripper fingers) are held at 0 by [`Robot::link_poses`], except
/// mimic joints ([`KinematicTree::mimic`]), which follow their leader's value.
///
/// When the chain is a 6R ortho-parallel arm with a spherical wrist (detected from
/// the geometry, see [`OpwSolver::detect`]) or a UR-type arm (axes 2-3-4 parallel,
/// offset wrist, see [`UrSolver::detect`]) a closed-form solver is used for inverse
/// kinematics, otherwise the numeric one ([`Robot::solver`] says which).
#[derive(Debug, Clone)]
pub struct Robot {
    name: String,
    tree: KinematicTree,
    base: Transform,
    flange: usize,
    tool: Transform,
    joints: Vec<usize>,
    /// How many of `joints` are on the flange chain (the rest are external axes).
    chain_dof: usize,
    chain: Vec<usize>,
    solver: IkSolver,
    limits_source: Option<String>,
}

/// The inverse-kinematics solver of a [`Robot`], chosen from its geometry when the
/// robot is built (or its tool or external axes change): one closed form per arm
/// type, the numeric solver for any other chain. [`Robot::inverse`] dispatches on it.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum IkSolver {
    /// Ortho-parallel arm with a spherical wrist ([`OpwSolver::detect`]).
    Opw(OpwSolver),
    /// UR-type arm: axes 2-3-4 parallel, offset wrist ([`UrSolver::detect`]).
    Ur(UrSolver),
    /// Any chain ([`NumericIk`], settings from the call's [`IkOptions`]).
    Numeric,
}

impl IkSolver {
    /// OPW first (a spherical wrist), then UR: the two geometries exclude each other
    /// except in degenerate cases, where the OPW solver is the established one.
    fn detect(robot: &Robot) -> Self {
        if let Ok(s) = OpwSolver::detect(robot) {
            IkSolver::Opw(s)
        } else if let Ok(s) = UrSolver::detect(robot) {
            IkSolver::Ur(s)
        } else {
            IkSolver::Numeric
        }
    }

    /// Which kind of solver this is.
    pub fn kind(&self) -> IkSolverKind {
        match self {
            IkSolver::Opw(_) => IkSolverKind::Opw,
            IkSolver::Ur(_) => IkSolverKind::Ur,
            IkSolver::Numeric => IkSolverKind::Numeric,
        }
    }
}

/// Which inverse-kinematics solver a [`Robot`] uses (chosen from its geometry).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IkSolverKind {
    /// Closed form, ortho-parallel arm with a spherical wrist ([`OpwSolver`]).
    Opw,
    /// Closed form, UR-type arm: axes 2-3-4 parallel, offset wrist ([`UrSolver`]).
    Ur,
    /// Numeric ([`NumericIk`]): any chain.
    Numeric,
}

impl IkSolverKind {
    /// `"opw"`, `"ur"` or `"numeric"`.
    pub fn name(self) -> &'static str {
        match self {
            IkSolverKind::Opw => "opw",
            IkSolverKind::Ur => "ur",
            IkSolverKind::Numeric => "numeric",
        }
    }
}

impl Robot {
    /// A robot from a tree, its flange link and the tool frame in the flange frame;
    /// the base pose is the identity.
    pub fn new(
        name: impl Into<String>,
        tree: KinematicTree,
        flange: usize,
        tool: Transform,
    ) -> Result<Self, KinematicsError> {
        let chain = tree
            .path_from_root(flange)
            .ok_or(KinematicsError::NoSuchLink(flange))?;
        // A mimic joint on the chain would need every solver to drive it from its
        // leader; the URDF reader never chooses such a flange by itself.
        if let Some(&i) = chain.iter().find(|&&i| tree.mimic(i).is_some()) {
            return Err(KinematicsError::InvalidDescription(
                DescriptionProblem::MimicOnChain {
                    link: tree.links()[i].name.clone().unwrap_or_default(),
                    leader: tree
                        .mimic(i)
                        .and_then(|m| tree.links()[m.leader].name.clone())
                        .unwrap_or_default(),
                },
            ));
        }
        let joints: Vec<usize> = chain
            .iter()
            .copied()
            .filter(|&i| tree.links()[i].joint.kind != JointKind::Fixed)
            .collect();
        if joints.is_empty() {
            return Err(KinematicsError::NoJoints);
        }
        if !tool.is_finite() {
            return Err(KinematicsError::InvalidDescription(
                DescriptionProblem::ToolNotFinite,
            ));
        }
        let mut robot = Self {
            name: name.into(),
            tree,
            base: Transform::IDENTITY,
            flange,
            tool,
            chain_dof: joints.len(),
            joints,
            chain,
            solver: IkSolver::Numeric,
            limits_source: None,
        };
        robot.detect_solver();
        Ok(robot)
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Where the joint limits come from (a public source, `unverified: …`, or `None`
    /// when the user supplied them).
    pub fn limits_source(&self) -> Option<&str> {
        self.limits_source.as_deref()
    }

    /// The same robot with a note on where its joint limits come from.
    #[must_use]
    pub fn with_limits_source(mut self, source: impl Into<String>) -> Self {
        self.limits_source = Some(source.into());
        self
    }

    /// Sets (or clears) the note on where the joint limits come from.
    pub fn set_limits_source(&mut self, source: Option<String>) {
        self.limits_source = source;
    }

    /// The same robot under another name.
    #[must_use]
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// The kinematic tree.
    pub fn tree(&self) -> &KinematicTree {
        &self.tree
    }

    /// World pose of the tree root (mm).
    pub fn base(&self) -> Transform {
        self.base
    }

    /// Sets the world pose of the tree root.
    pub fn set_base(&mut self, base: Transform) {
        self.base = base;
    }

    /// The same robot placed at `base`.
    #[must_use]
    pub fn with_base(mut self, base: Transform) -> Self {
        self.base = base;
        self
    }

    /// The flange link index.
    pub fn flange(&self) -> usize {
        self.flange
    }

    /// The tool centre point frame in the flange frame (mm).
    pub fn tool(&self) -> Transform {
        self.tool
    }

    /// Sets the tool frame (in the flange frame) and re-derives the analytic solver.
    pub fn set_tool(&mut self, tool: Transform) {
        self.tool = tool;
        self.detect_solver();
    }

    fn detect_solver(&mut self) {
        self.solver = IkSolver::detect(self);
    }

    /// The same robot with another tool frame.
    #[must_use]
    pub fn with_tool(mut self, tool: Transform) -> Self {
        self.set_tool(tool);
        self
    }

    /// Number of joints (degrees of freedom), external axes included.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Number of joints on the chain from the root to the flange: the first
    /// `chain_dof` values of a joint vector; the rest are external axes.
    pub fn chain_dof(&self) -> usize {
        self.chain_dof
    }

    /// Link indices of the external axes, in joint order (after the chain's joints).
    pub fn external_axes(&self) -> &[usize] {
        &self.joints[self.chain_dof..]
    }

    /// The same robot with **external axes**: movable links off the flange chain (a
    /// turntable or an XY table carrying the work, gripper fingers) that are joints of
    /// the robot all the same, appended to the joint vector after the chain's joints in
    /// the order given. They move their links in [`Robot::link_poses`] but not the
    /// flange; inverse kinematics solves the chain and keeps them at the reference's
    /// values. A robot with external axes uses the numeric solver (the closed forms
    /// are for 6-joint chains).
    ///
    /// # Errors
    /// [`KinematicsError::InvalidLink`]: a link that does not exist, is fixed, lies on
    /// the flange chain, follows a mimic joint or is listed twice.
    pub fn with_external_axes(mut self, links: &[usize]) -> Result<Self, KinematicsError> {
        for (k, &i) in links.iter().enumerate() {
            let bad = |cause: LinkProblem| KinematicsError::InvalidLink {
                link: i,
                name: self
                    .tree
                    .links()
                    .get(i)
                    .and_then(|l| l.name.clone())
                    .unwrap_or_default(),
                cause,
            };
            let Some(link) = self.tree.links().get(i) else {
                return Err(KinematicsError::NoSuchLink(i));
            };
            if !link.joint.kind.is_movable() {
                return Err(bad(LinkProblem::ExternalFixed));
            }
            if self.chain.contains(&i) {
                return Err(bad(LinkProblem::ExternalOnChain));
            }
            if self.tree.mimic(i).is_some() {
                return Err(bad(LinkProblem::ExternalMimic));
            }
            if links[..k].contains(&i) {
                return Err(bad(LinkProblem::ExternalTwice));
            }
        }
        self.joints.truncate(self.chain_dof);
        self.joints.extend_from_slice(links);
        self.detect_solver();
        Ok(self)
    }

    /// Link indices of the joints, in joint order.
    pub fn joint_links(&self) -> &[usize] {
        &self.joints
    }

    /// Kind of each joint, in joint order.
    pub fn joint_kinds(&self) -> Vec<JointKind> {
        self.joints
            .iter()
            .map(|&i| self.tree.links()[i].joint.kind)
            .collect()
    }

    /// Limits of each joint (rad or mm), in joint order.
    pub fn joint_limits(&self) -> Vec<Option<JointLimits>> {
        self.joints
            .iter()
            .map(|&i| self.tree.links()[i].joint.limits)
            .collect()
    }

    /// Index of the first joint whose value lies outside its limits (tolerance 1e-9).
    pub fn limit_violation(&self, q: &[f64]) -> Option<usize> {
        self.joints.iter().zip(q).position(|(&i, &v)| {
            self.tree.links()[i]
                .joint
                .limits
                .is_some_and(|l| !l.contains(v, 1e-9))
        })
    }

    /// The OPW closed-form solver, when the robot qualifies.
    pub fn analytic(&self) -> Option<&OpwSolver> {
        match &self.solver {
            IkSolver::Opw(s) => Some(s),
            _ => None,
        }
    }

    /// The UR closed-form solver, when the robot qualifies (and is not OPW).
    pub fn ur_solver(&self) -> Option<&UrSolver> {
        match &self.solver {
            IkSolver::Ur(s) => Some(s),
            _ => None,
        }
    }

    /// The solver [`Robot::inverse`] uses.
    pub fn ik_solver(&self) -> &IkSolver {
        &self.solver
    }

    /// Which solver [`Robot::inverse`] uses.
    pub fn solver(&self) -> IkSolverKind {
        self.solver.kind()
    }

    /// The solver's name: `"opw"`, `"ur"` or `"numeric"`.
    pub fn solver_name(&self) -> &'static str {
        self.solver().name()
    }

    /// Whether inverse kinematics is solved in closed form (OPW or UR).
    pub fn closed_form(&self) -> bool {
        self.solver() != IkSolverKind::Numeric
    }

    /// Why the robot does not qualify for the closed-form solver (`None` if it does).
    pub fn analytic_rejection(&self) -> Option<super::NotOpw> {
        OpwSolver::detect(self).err()
    }

    fn check(&self, q: &[f64]) -> Result<(), KinematicsError> {
        if q.len() != self.joints.len() {
            return Err(KinematicsError::JointCount {
                expected: self.joints.len(),
                got: q.len(),
            });
        }
        if let Some(i) = q.iter().position(|v| !v.is_finite()) {
            return Err(KinematicsError::NonFiniteJoint(i));
        }
        Ok(())
    }

    /// Flange pose in the root frame without checks (q has `dof` finite values).
    #[inline]
    pub(crate) fn flange_in_root(&self, q: &[f64]) -> Isometry3<f64> {
        let mut pose = Isometry3::identity();
        let mut k = 0;
        let links = self.tree.links();
        for &i in &self.chain {
            let link = &links[i];
            let home = link.home.isometry();
            match link.joint.kind {
                JointKind::Fixed => pose *= home,
                JointKind::Revolute => {
                    // pose · M(q) · home with M the rotation r about the axis line through
                    // p, folded: t += R_pose·(p + r·(t_home − p)), R = R_pose·r·R_home.
                    let p = link.joint.point.coords;
                    let r = UnitQuaternion::from_axis_angle(
                        &Unit::new_unchecked(link.joint.axis),
                        q[k],
                    );
                    let local = p + r * (home.translation.vector - p);
                    pose = Isometry3::from_parts(
                        Translation3::from(pose.translation.vector + pose.rotation * local),
                        pose.rotation * r * home.rotation,
                    );
                    k += 1;
                }
                JointKind::Prismatic => {
                    pose = pose * link.joint.motion(q[k]) * home;
                    k += 1;
                }
            }
        }
        pose
    }

    /// World poses of every link of the tree for joint values `q` (joint order).
    pub fn link_poses(&self, q: &[f64]) -> Result<Vec<Transform>, KinematicsError> {
        self.check(q)?;
        let mut values = vec![0.0; self.tree.len()];
        for (&i, &v) in self.joints.iter().zip(q) {
            values[i] = v;
        }
        self.tree.link_poses(&self.base, &values)
    }

    /// World pose of the flange for joint values `q`.
    pub fn flange_pose(&self, q: &[f64]) -> Result<Transform, KinematicsError> {
        self.check(q)?;
        Ok(Transform::from_isometry(
            self.base.isometry() * self.flange_in_root(q),
        ))
    }

    /// World pose of the tool centre point for joint values `q`.
    pub fn tcp_pose(&self, q: &[f64]) -> Result<Transform, KinematicsError> {
        self.check(q)?;
        Ok(Transform::from_isometry(
            self.base.isometry() * self.flange_in_root(q) * self.tool.isometry(),
        ))
    }

    /// The TCP pose as `[x, y, z, a, b, c]` (mm, radians in `conv`).
    pub fn tcp_xyzabc(
        &self,
        q: &[f64],
        conv: AngleConvention,
    ) -> Result<[f64; 6], KinematicsError> {
        Ok(self.tcp_pose(q)?.to_xyzabc(conv))
    }

    /// TCP pose in the root frame without checks.
    #[inline]
    pub(crate) fn tcp_in_root(&self, q: &[f64]) -> Isometry3<f64> {
        self.flange_in_root(q) * self.tool.isometry()
    }

    /// All joint solutions placing the TCP at the world pose `target`, within the
    /// joint limits, sorted by distance to `reference` (the current configuration).
    ///
    /// Uses a closed-form solver when the robot qualifies (every branch, with ±360°
    /// variants allowed by the limits), else the numeric solver with
    /// `options.numeric` settings. Errors name the cause: unreachable, singular,
    /// outside the joint limits.
    pub fn inverse(
        &self,
        target: &Transform,
        reference: &[f64],
        options: &IkOptions,
    ) -> Result<Vec<IkSolution>, IkError> {
        let local = self.local_target(target, reference)?;
        match &self.solver {
            IkSolver::Opw(s) => closed_form::solve(s, Some(self), &local, reference, options),
            IkSolver::Ur(s) => closed_form::solve(s, Some(self), &local, reference, options),
            IkSolver::Numeric => NumericIk::from_options(options).solve(self, &local, reference),
        }
    }

    /// The checks of [`Robot::inverse`] and the target in the root frame.
    fn local_target(&self, target: &Transform, reference: &[f64]) -> Result<Transform, IkError> {
        self.check(reference).map_err(IkError::Input)?;
        if !target.is_finite() {
            return Err(IkError::Input(KinematicsError::InvalidDescription(
                DescriptionProblem::TargetNotFinite,
            )));
        }
        Ok(Transform::from_isometry(
            self.base.isometry().inverse() * target.isometry(),
        ))
    }

    /// The closed-form solutions of [`Robot::inverse`] with their joints inline (none
    /// for the numeric solver).
    fn inverse_inline(
        &self,
        target: &Transform,
        reference: &[f64],
        options: &IkOptions,
    ) -> Option<Result<Vec<closed_form::Solution6>, IkError>> {
        let solve = |local: &Transform| match &self.solver {
            IkSolver::Opw(s) => Some(closed_form::solve(s, Some(self), local, reference, options)),
            IkSolver::Ur(s) => Some(closed_form::solve(s, Some(self), local, reference, options)),
            IkSolver::Numeric => None,
        };
        match self.local_target(target, reference) {
            Ok(local) => solve(&local),
            Err(e) => Some(Err(e)),
        }
    }

    /// The joints of each solution of [`Robot::inverse`] (the same solutions in the
    /// same order, `dof` values each, rad/mm) passed to `visit`, without a `Vec` per
    /// solution: what a caller that copies the joints elsewhere (the script and
    /// Python bindings) needs. Returns the number of solutions.
    ///
    /// # Errors
    /// As [`Robot::inverse`].
    pub fn inverse_each(
        &self,
        target: &Transform,
        reference: &[f64],
        options: &IkOptions,
        mut visit: impl FnMut(&[f64]),
    ) -> Result<usize, IkError> {
        match self.inverse_inline(target, reference, options) {
            Some(sols) => {
                let sols = sols?;
                sols.iter().for_each(|s| visit(&s.joints));
                Ok(sols.len())
            }
            None => {
                let sols = self.inverse(target, reference, options)?;
                sols.iter().for_each(|s| visit(&s.joints));
                Ok(sols.len())
            }
        }
    }

    /// The solution nearest to `reference` (see [`Robot::inverse`]).
    pub fn inverse_nearest(
        &self,
        target: &Transform,
        reference: &[f64],
        options: &IkOptions,
    ) -> Result<IkSolution, IkError> {
        let none = || IkError::Unreachable(super::Unreachable::NoSolution);
        match self.inverse_inline(target, reference, options) {
            // Only the nearest becomes an `IkSolution` (one allocation).
            Some(sols) => sols?.first().map(|&s| s.into()).ok_or_else(none),
            None => {
                let mut all = self.inverse(target, reference, options)?;
                if all.is_empty() {
                    return Err(none());
                }
                Ok(all.swap_remove(0))
            }
        }
    }

    /// Inverse kinematics along a sequence of world poses (mm): for each pose in
    /// `targets`, the solution nearest to the previous pose's solution (the first
    /// nearest to `start`, rad / mm), or `None` when the pose has no solution within the
    /// joint limits (the next pose is then solved near the last solution found). The
    /// robot does not move. This is what a loop over thousands of poses should call: one
    /// solver set-up, no per-pose overhead of the caller.
    pub fn inverse_chain(
        &self,
        targets: &[Transform],
        start: &[f64],
        options: &IkOptions,
    ) -> Vec<Option<IkSolution>> {
        let mut reference = start.to_vec();
        targets
            .iter()
            .map(|t| {
                let sol = self.inverse_nearest(t, &reference, options).ok()?;
                reference.clone_from(&sol.joints);
                Some(sol)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::kinematics::{Catalog, IkOptions};
    use crate::math::{Transform, Vec3};

    /// Each pose of a chain is solved near the previous solution: FK of the solutions
    /// gives the targets back, a pose out of reach is `None` without breaking the
    /// chain, and a path of nearby poses gets nearby joints (no branch flips).
    #[test]
    fn inverse_chain_follows_the_previous_solution() {
        let robot = Catalog::NachiMz07.robot();
        let start: Vec<f64> = [10.0f64, -20.0, 30.0, 40.0, -50.0, 60.0]
            .iter()
            .map(|v| v.to_radians())
            .collect();
        let mut targets: Vec<Transform> = (0..20)
            .map(|k| {
                let mut q = start.clone();
                q[0] += 0.01 * k as f64;
                q[4] += 0.005 * k as f64;
                robot.tcp_pose(&q).unwrap()
            })
            .collect();
        targets.insert(5, Transform::from_translation(Vec3::new(1e5, 0.0, 0.0)));
        let out = robot.inverse_chain(&targets, &start, &IkOptions::default());
        assert_eq!(out.len(), targets.len());
        assert!(out[5].is_none());
        let mut previous = start.clone();
        for (t, s) in targets.iter().zip(&out) {
            let Some(s) = s else { continue };
            assert!(robot.tcp_pose(&s.joints).unwrap().approx_eq(t, 1e-6, 1e-9));
            let step = s
                .joints
                .iter()
                .zip(&previous)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                step < 0.05,
                "joint step {step} rad between neighbouring poses"
            );
            previous.clone_from(&s.joints);
        }
    }
}
