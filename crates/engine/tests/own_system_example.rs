//! The engine's example of a user's own system (`examples/own_system.rs`) runs to its end:
//! its branch is followed over the whole range and its stable orbit agrees with direct
//! time integration (the example returns an error otherwise).

#[path = "../examples/own_system.rs"]
#[allow(dead_code)]
mod example;

#[test]
fn the_own_system_example_runs_and_agrees_with_time_integration() {
    example::check().expect("example");
}
