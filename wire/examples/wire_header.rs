//! Prints `wire/include/dicstream_wire.h`, the C/C++ header of the shared-memory layouts
//! (`wire::layouts::c_header`):
//!
//! ```text
//! cargo run --release -p wire --example wire_header > wire/include/dicstream_wire.h
//! ```

fn main() {
    print!("{}", wire::layouts::c_header());
}
