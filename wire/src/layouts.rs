//! The shared-memory layouts described once, for the readers outside Rust: each layout's
//! fields with their offsets, sizes, element types and counts, taken from the Rust
//! definitions themselves (`offset_of!`, `size_of`, the field's type through [`Described`]);
//! only the list of field names is written here, and [`Layout::gaps`] (tested) fails when a
//! field of the struct is missing from it. The Python package builds its numpy dtypes from
//! these at run time, and [`c_header`] writes `wire/include/dicstream_wire.h` (for C and C++
//! users of iceoryx2), held equal to the committed file by a test.
//!
//! [`LayoutVersionError`] is the one layout-version check of every reader (frames, fields,
//! rig states, identification reports, specimen solves).

use crate::field::{FieldHeader, FieldNode, GaugeStrain};
use crate::frame::{FrameHeader, GroundTruth};
use crate::identification::{IdentificationReport, RankedModel};
use crate::rig::{ActuatorState, RigState};
use std::mem::{align_of, offset_of, size_of};

mod c_header;

pub use c_header::c_header;

/// A layout's version is not this build's [`crate::LAYOUT_VERSION`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "{layout} layout version {found} but this build reads version {}",
    crate::LAYOUT_VERSION
)]
pub struct LayoutVersionError {
    /// What was read: "frame", "field", "rig state", ...
    pub layout: &'static str,
    pub found: u32,
}

/// The check every reader makes of a sample's `layout_version`.
pub fn check_version(layout: &'static str, found: u32) -> Result<(), LayoutVersionError> {
    match found == crate::LAYOUT_VERSION {
        true => Ok(()),
        false => Err(LayoutVersionError { layout, found }),
    }
}

/// A plain number type of the layouts (little-endian, as every supported target).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    U8,
    U16,
    U32,
    U64,
    F32,
    F64,
}

impl Scalar {
    pub fn size_bytes(self) -> usize {
        match self {
            Scalar::U8 => 1,
            Scalar::U16 => 2,
            Scalar::U32 | Scalar::F32 => 4,
            Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// numpy's type string (`<f4`, ...).
    pub fn numpy(self) -> &'static str {
        match self {
            Scalar::U8 => "u1",
            Scalar::U16 => "<u2",
            Scalar::U32 => "<u4",
            Scalar::U64 => "<u8",
            Scalar::F32 => "<f4",
            Scalar::F64 => "<f8",
        }
    }

    /// The C type (`<stdint.h>`).
    pub fn c(self) -> &'static str {
        match self {
            Scalar::U8 => "uint8_t",
            Scalar::U16 => "uint16_t",
            Scalar::U32 => "uint32_t",
            Scalar::U64 => "uint64_t",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }
}

/// What one element of a field is: a number, or a layout of its own.
#[derive(Debug, Clone, Copy)]
pub enum Element {
    Scalar(Scalar),
    Layout(fn() -> Layout),
}

/// One field of a layout: `count` elements (1, or an array's length) at `offset`.
#[derive(Debug, Clone)]
pub struct Field {
    pub name: &'static str,
    pub offset_bytes: usize,
    pub size_bytes: usize,
    pub element: Element,
    pub count: usize,
}

/// One `#[repr(C)]` type of the wire.
#[derive(Debug, Clone)]
pub struct Layout {
    /// The Rust (and C) type name.
    pub name: &'static str,
    pub size_bytes: usize,
    pub align_bytes: usize,
    pub fields: Vec<Field>,
}

impl Layout {
    /// The byte ranges of the type that no listed field covers (padding, or a field missing
    /// from the description), and the overlaps, as text; empty when the fields tile the type.
    pub fn gaps(&self) -> Vec<String> {
        let mut problems = Vec::new();
        let mut end = 0;
        for field in &self.fields {
            if field.offset_bytes != end {
                problems.push(format!(
                    "{}: bytes {end}..{} before {} are not described",
                    self.name, field.offset_bytes, field.name
                ));
            }
            end = field.offset_bytes + field.size_bytes;
        }
        if end != self.size_bytes {
            problems.push(format!(
                "{}: bytes {end}..{} at the end are not described",
                self.name, self.size_bytes
            ));
        }
        problems
    }

    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }
}

/// A type a layout's field can have: its element and how many.
pub trait Described {
    fn element() -> Element;
    fn count() -> usize {
        1
    }
}

macro_rules! scalar {
    ($($ty:ty => $scalar:ident),*) => {
        $(impl Described for $ty {
            fn element() -> Element {
                Element::Scalar(Scalar::$scalar)
            }
        })*
    };
}
scalar!(u8 => U8, u16 => U16, u32 => U32, u64 => U64, f32 => F32, f64 => F64);

impl<T: Described, const N: usize> Described for [T; N] {
    fn element() -> Element {
        T::element()
    }
    fn count() -> usize {
        N * T::count()
    }
}

/// The field `name` at `offset_bytes` of a `T`, of the type `of` returns.
fn field<T, F: Described>(name: &'static str, offset_bytes: usize, _of: fn(&T) -> &F) -> Field {
    Field {
        name,
        offset_bytes,
        size_bytes: size_of::<F>(),
        element: F::element(),
        count: F::count(),
    }
}

/// The layout of `$ty` with the fields named, in their order, and its [`Described`] impl.
macro_rules! describe {
    ($fn_name:ident, $ty:ident { $($field:ident),* $(,)? }) => {
        pub fn $fn_name() -> Layout {
            Layout {
                name: stringify!($ty),
                size_bytes: size_of::<$ty>(),
                align_bytes: align_of::<$ty>(),
                fields: vec![$(field(
                    stringify!($field),
                    offset_of!($ty, $field),
                    |v: &$ty| &v.$field,
                )),*],
            }
        }

        impl Described for $ty {
            fn element() -> Element {
                Element::Layout($fn_name)
            }
        }
    };
}

describe!(
    ground_truth,
    GroundTruth {
        deformation_gradient,
        translation_px,
        centre_px,
        specimen_solve_id,
        specimen_grip_mm,
    }
);
describe!(
    frame_header,
    FrameHeader {
        layout_version,
        bit_depth,
        frame_id,
        t_capture_ns,
        width_px,
        height_px,
        rig_sample_id,
        scenario_id,
        has_truth,
        truth,
        pixel_checksum,
        sequence_id,
        reserved,
        t_camera_ns,
    }
);
describe!(
    field_node,
    FieldNode {
        x_px,
        y_px,
        u_px,
        v_px,
        exx,
        eyy,
        exy,
        score,
        iterations,
        status,
        du_dx,
        du_dy,
        dv_dx,
        dv_dy,
    }
);
describe!(gauge_strain, GaugeStrain { exx, eyy, exy });
describe!(
    field_header,
    FieldHeader {
        layout_version,
        strain_measure,
        frame_id,
        reference_frame_id,
        origin_frame_id,
        t_capture_ns,
        rig_sample_id,
        t_received_ns,
        t_published_ns,
        correlate_ns,
        frames_dropped,
        mesh_cols,
        mesh_rows,
        zoi_px,
        step_px,
        valid_nodes,
        has_truth,
        truth,
        u_mean_px,
        v_mean_px,
        gauge,
        sequence_id,
        gradient_source,
    }
);
describe!(
    actuator_state,
    ActuatorState {
        position_mm,
        command_mm,
        following_error_mm,
        force_kn,
        mode,
        limit_flags,
    }
);
describe!(
    rig_state,
    RigState {
        layout_version,
        program_state,
        sample_id,
        t_sim_s,
        t_published_ns,
        actuators,
        axis_centre_mm,
        axis_elongation_mm,
        specimen_stretch_x,
        specimen_stretch_y,
        specimen_rotation_rad,
        specimen_centre_offset_mm,
        specimen_section_x_mm2,
        specimen_section_y_mm2,
        load_case,
        hydraulics_on,
        test_index,
        control_mode,
        target_log_exx,
        target_log_eyy,
        specimen_solve_id,
        specimen_grip_mm,
    }
);
describe!(ranked_model, RankedModel { name, aic, rms_mpa });
describe!(
    identification_report,
    IdentificationReport {
        layout_version,
        points,
        frame_id,
        t_capture_ns,
        t_published_ns,
        a,
        a_stderr,
        b,
        b_stderr,
        a_count,
        b_count,
        rms_mpa,
        ranked_count,
        route,
        ranking,
    }
);

/// Every described layout, nested ones before those that hold them (the C header's order).
pub fn all() -> Vec<Layout> {
    vec![
        ground_truth(),
        frame_header(),
        field_node(),
        gauge_strain(),
        field_header(),
        actuator_state(),
        rig_state(),
        ranked_model(),
        identification_report(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layout_is_described_whole_without_padding() {
        for layout in all() {
            assert_eq!(layout.gaps(), Vec::<String>::new());
            for f in &layout.fields {
                let element_bytes = match f.element {
                    Element::Scalar(s) => s.size_bytes(),
                    Element::Layout(nested) => nested().size_bytes,
                };
                assert_eq!(
                    element_bytes * f.count,
                    f.size_bytes,
                    "{}.{}",
                    layout.name,
                    f.name
                );
            }
        }
    }

    #[test]
    fn a_missing_field_is_a_gap() {
        let mut layout = field_node();
        layout.fields.remove(3);
        assert_eq!(
            layout.gaps(),
            ["FieldNode: bytes 12..16 before exx are not described"]
        );
        let mut layout = gauge_strain();
        layout.fields.pop();
        assert_eq!(
            layout.gaps(),
            ["GaugeStrain: bytes 16..24 at the end are not described"]
        );
    }

    #[test]
    fn fields_carry_the_rust_offsets_types_and_counts() {
        let header = field_header();
        let gauge = header.field("gauge").unwrap();
        assert_eq!((gauge.offset_bytes, gauge.count), (224, 4));
        assert!(matches!(gauge.element, Element::Layout(f) if f().name == "GaugeStrain"));
        let node = field_node();
        let status = node.field("status").unwrap();
        assert_eq!((status.offset_bytes, status.size_bytes), (36, 4));
        assert!(matches!(status.element, Element::Scalar(Scalar::U32)));
        let ranking = identification_report();
        let name = ranked_model();
        assert_eq!(ranking.field("ranking").unwrap().count, 8);
        assert_eq!(name.field("name").unwrap().count, 24);
    }

    #[test]
    fn the_version_check_names_the_layout_and_both_versions() {
        assert_eq!(check_version("field", crate::LAYOUT_VERSION), Ok(()));
        let error = check_version("rig state", 2).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "rig state layout version 2 but this build reads version {}",
                crate::LAYOUT_VERSION
            )
        );
    }
}
