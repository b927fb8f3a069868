//! The robots the benchmarks measure, from `example-robot-data`: name, URDF under its
//! `robots/` folder, base. `docs/robots/pinocchio_check.py` checks the same robots.

pub const ROBOTS: [(&str, &str, &str); 5] = [
    ("ur5", "ur_description/urdf/ur5_robot.urdf", "fixed"),
    ("panda", "panda_description/urdf/panda.urdf", "fixed"),
    ("solo12", "solo_description/robots/solo12.urdf", "floating"),
    ("anymal", "anymal_b_simple_description/robots/anymal.urdf", "floating"),
    ("talos_reduced", "talos_data/robots/talos_reduced.urdf", "floating"),
];
