//! The process shells of the member crates, each run in a thread of this test against real
//! iceoryx2 shared memory, with the test as its peers: the rig's (state and commands, strain
//! control over fields), the identifier's (a live identification) and the wire's round trip.
//!
//! One test binary for all of them, in the root package: each test that publishes or
//! subscribes compiles wire's generic iceoryx2 ports for its types, 30 to 70 s per binary in
//! release; as four binaries in their crates they cost 200 s of a 2-core build, as one about a
//! third of it. They stay apart from `tests/processes/` (whole `dicstream` runs, six at a
//! time): the rig's strain test judges a hold within 0.4 s of its real time.
//! `cargo test --release --test shells rig_` runs the rig's.

mod identifier_process;
mod rig_options;
mod rig_process;
mod rig_strain_process;
mod wire_round_trip;
