//! Assembly sequences: which component goes on which, in what order and direction
//! (seed 003's task layer). Units: millimetres and radians, assembly frame.

mod task;

pub use task::{Grasp, Operation, Task};
