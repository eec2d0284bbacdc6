//! `wire/include/dicstream_wire.h`: the described layouts as C structs (C11 and C++), each with
//! its iceoryx2 type name (`IOX2_TYPE_NAME`, what iceoryx2's C++ bindings match a Rust
//! `#[type_name]` with) and static assertions of its size and every field's offset, so a C or
//! C++ compiler that lays a struct out otherwise refuses the header.

use super::{Element, Layout};
use std::fmt::Write;

/// The C name of a described type.
fn c_name(rust_name: &str) -> String {
    format!("Dicstream{rust_name}")
}

/// The iceoryx2 type name of a described type (its Rust `#[type_name]`).
pub(crate) fn type_name(rust_name: &str) -> String {
    format!("dicstream.{rust_name}.v{}", crate::LAYOUT_VERSION)
}

/// The header's text, from [`super::all`], the services and [`crate::LAYOUT_VERSION`].
pub fn c_header() -> String {
    let mut h = String::new();
    let version = crate::LAYOUT_VERSION;
    // Writing to a String cannot fail.
    let _ = writeln!(
        h,
        "/* dicstream_wire.h: the shared-memory layouts of dicstream's services, layout version \
         {version}.\n * Generated from the Rust definitions (wire::layouts::c_header): do not \
         edit. Regenerate with\n *   cargo run --release -p wire --example wire_header > \
         wire/include/dicstream_wire.h\n * Services (iceoryx2 publish-subscribe, with an event \
         service of the same name) live under\n * the instance's prefix \"<instance>_\" \
         (wire::instance). frames: a uint16_t slice (row-major\n * pixels) behind a \
         DicstreamFrameHeader; fields: a DicstreamFieldNode slice (row-major mesh)\n * behind \
         a DicstreamFieldHeader; rig/state: a DicstreamRigState; identification: a\n * \
         DicstreamIdentificationReport. Every reader checks layout_version first. */"
    );
    h.push_str("#ifndef DICSTREAM_WIRE_H\n#define DICSTREAM_WIRE_H\n\n");
    h.push_str("#include <stddef.h>\n#include <stdint.h>\n\n");
    h.push_str("#ifdef __cplusplus\n#define DICSTREAM_STATIC_ASSERT static_assert\n#else\n");
    h.push_str("#define DICSTREAM_STATIC_ASSERT _Static_assert\n#endif\n\n");
    let _ = writeln!(h, "#define DICSTREAM_LAYOUT_VERSION {version}u");
    for spec in crate::services::TAPPABLE {
        let macro_name = spec.name.replace('/', "_").to_uppercase();
        let _ = writeln!(
            h,
            "#define DICSTREAM_SERVICE_{macro_name} \"{}\"",
            spec.name
        );
    }
    for layout in super::all() {
        h.push('\n');
        write_struct(&mut h, &layout);
    }
    h.push_str("\n#endif /* DICSTREAM_WIRE_H */\n");
    h
}

fn write_struct(h: &mut String, layout: &Layout) {
    let name = c_name(layout.name);
    let _ = writeln!(h, "typedef struct {name} {{");
    for field in &layout.fields {
        let ty = match field.element {
            Element::Scalar(s) => s.c().to_string(),
            Element::Layout(nested) => c_name(nested().name),
        };
        let array = match field.count {
            1 => String::new(),
            n => format!("[{n}]"),
        };
        let _ = writeln!(h, "    {ty} {}{array};", field.name);
    }
    h.push_str("#ifdef __cplusplus\n");
    let _ = writeln!(
        h,
        "    static constexpr const char* IOX2_TYPE_NAME = \"{}\";",
        type_name(layout.name)
    );
    h.push_str("#endif\n");
    let _ = writeln!(h, "}} {name};");
    let _ = writeln!(
        h,
        "DICSTREAM_STATIC_ASSERT(sizeof({name}) == {}, \"{name} size\");",
        layout.size_bytes
    );
    for field in &layout.fields {
        let _ = writeln!(
            h,
            "DICSTREAM_STATIC_ASSERT(offsetof({name}, {f}) == {}, \"{name}.{f} offset\");",
            field.offset_bytes,
            f = field.name
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn committed_path() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("include/dicstream_wire.h")
    }

    #[test]
    fn the_committed_header_is_the_generated_one() {
        let path = committed_path();
        let committed =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            committed == c_header(),
            "{} differs from the layouts: regenerate it with `cargo run --release -p wire \
             --example wire_header > wire/include/dicstream_wire.h`",
            path.display()
        );
    }

    /// The header's static assertions hold for the C and C++ compilers found (`cc`, `c++`):
    /// they lay the structs out as Rust does.
    #[test]
    fn c_and_cpp_compilers_accept_the_header() {
        let path = committed_path();
        for (compiler, language, standard) in
            [("cc", "c", "-std=c11"), ("c++", "c++", "-std=c++17")]
        {
            let run = std::process::Command::new(compiler)
                .args([
                    standard,
                    "-fsyntax-only",
                    "-Wall",
                    "-Werror",
                    "-x",
                    language,
                ])
                .arg(&path)
                .output();
            match run {
                Ok(out) => assert!(
                    out.status.success(),
                    "{compiler} refused {}: {}",
                    path.display(),
                    String::from_utf8_lossy(&out.stderr)
                ),
                Err(e) => {
                    assert!(std::env::var_os("CI").is_none(), "CI needs {compiler}: {e}");
                    eprintln!("skipped: no {compiler} here ({e})");
                }
            }
        }
    }

    #[cfg(feature = "ipc")]
    #[test]
    fn type_names_are_the_rust_ones() {
        use crate::*;
        use iceoryx2::prelude::ZeroCopySend;
        // SAFETY: type_name only returns the `#[type_name]` string.
        let rust = unsafe {
            [
                GroundTruth::type_name(),
                FrameHeader::type_name(),
                FieldNode::type_name(),
                GaugeStrain::type_name(),
                FieldHeader::type_name(),
                ActuatorState::type_name(),
                RigState::type_name(),
                identification::RankedModel::type_name(),
                IdentificationReport::type_name(),
            ]
        };
        let described: Vec<String> = super::super::all()
            .iter()
            .map(|l| type_name(l.name))
            .collect();
        assert_eq!(described, rust);
    }
}
