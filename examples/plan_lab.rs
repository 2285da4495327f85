//! scratch: not committed
use fitup::planning::problems;
use fitup::planning::{InsertionOptions, LazyValidation, Smoothing};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = &args[1];
    let seeds: u64 = args.get(2).map_or(3, |s| s.parse().unwrap());
    let limit: f64 = args.get(3).map_or(10000.0, |s| s.parse().unwrap());
    let p = problems::by_name(name).unwrap().unwrap();
    for seed in 0..seeds {
        let mut v = p.validator(p.default_validator_options()).unwrap();
        let mut plan = InsertionOptions::default().with_limits(seed, 100000);
        plan.smoothing = Smoothing::OFF;
        plan.time_limit_ms = Some(limit);
        let lazy: f64 = std::env::var("LAZY").ok().map_or(1.0, |s| s.parse().unwrap());
        let lz = (lazy > 0.0).then_some(LazyValidation { step_mm: lazy });
        plan.approach.lazy = lz;
        let rm: usize = std::env::var("RM").ok().map_or(0, |s| s.parse().unwrap());
        if let Some(l) = plan.approach.lattice.as_mut() { l.random_moves = rm; }
        if let fitup::planning::DisassemblyPlanner::LocalRrt(o) = &mut plan.disassembly { o.lattice.random_moves = rm; }
        let iters: usize = std::env::var("ITERS").ok().map_or(100000, |s| s.parse().unwrap());
        plan.approach.limits.max_iterations = iters;
        plan.disassembly.rrt_mut().limits.max_iterations = iters;
        if std::env::var_os("LAZY_DIS").is_some() {
            plan.disassembly.rrt_mut().lazy = lz;
        }
        let t0 = Instant::now();
        let path = p.solve_with(&mut v, &plan).unwrap();
        let dt = t0.elapsed().as_secs_f64();
        let s = v.stats();
        println!(
            "{name} seed {seed}: found {} {:?} in {dt:.3} s, iters {} nodes {} poses {} edges {} clear {} pairs {} keys {} planner {}",
            path.found(), path.failure, path.iterations, path.nodes, s.pose_checks, s.edge_checks, s.clearance_checks, s.pair_queries, path.poses.len(), path.planner
        );
    }
}
