//! The layouts as bytes: a sample's header and payload read as the bytes they are in shared
//! memory, and bytes written back into a typed header or slice. What carries a sample beyond
//! one host (the link, `dicstream link`) sends these bytes, so the far side receives the very
//! layout, version field included, and checks it as any reader does.
//!
//! Only the types below are [`Plain`]: `#[repr(C)]` numbers and arrays of numbers, without
//! padding (`layouts`' test checks that their described fields tile them), for which every
//! byte pattern is a valid value.

use crate::{FieldHeader, FieldNode, FrameHeader, IdentificationReport, RigState, SpecimenHeader};

/// A wire layout (or pixel) whose bytes are all initialised and any of whose byte patterns is
/// a valid value.
///
/// # Safety
/// Implement only for `#[repr(C)]` types made of integers and floats (or arrays and nested
/// `Plain` types of them) without padding.
pub unsafe trait Plain: Copy + 'static {}

// SAFETY: u16 is a plain number.
unsafe impl Plain for u16 {}
// SAFETY: the layouts below are `#[repr(C)]` numbers without padding: `layouts`'
// `every_layout_is_described_whole_without_padding` checks it for each.
unsafe impl Plain for FrameHeader {}
// SAFETY: as above.
unsafe impl Plain for FieldHeader {}
// SAFETY: as above.
unsafe impl Plain for FieldNode {}
// SAFETY: as above.
unsafe impl Plain for RigState {}
// SAFETY: as above.
unsafe impl Plain for IdentificationReport {}
// SAFETY: `#[repr(C)]` numbers whose offsets `layout_check.rs` asserts at compile time, 104
// bytes: 4 + 4 + 8 + 8 + 4 + 4 + 8 + 32 + 32, no padding.
unsafe impl Plain for SpecimenHeader {}
// SAFETY: f64 is a plain number (a specimen's payload).
unsafe impl Plain for f64 {}

/// The bytes of `values` as they lie in memory.
pub fn slice_bytes<T: Plain>(values: &[T]) -> &[u8] {
    // SAFETY: a Plain type has no padding, so every byte is initialised; u8 has no alignment
    // requirement; the length is the slice's size in bytes.
    unsafe {
        std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), std::mem::size_of_val(values))
    }
}

/// The bytes of one value.
pub fn value_bytes<T: Plain>(value: &T) -> &[u8] {
    slice_bytes(std::slice::from_ref(value))
}

/// The value whose bytes are `bytes`; None unless `bytes` is exactly one `T` long.
pub fn read_value<T: Plain>(bytes: &[u8]) -> Option<T> {
    (bytes.len() == size_of::<T>()).then(|| {
        // SAFETY: `bytes` holds size_of::<T>() initialised bytes, any pattern of which is a
        // valid T (Plain); read_unaligned needs no alignment.
        unsafe { std::ptr::read_unaligned(bytes.as_ptr().cast::<T>()) }
    })
}

/// How many `T` the bytes hold; None when they are not a whole number of them.
pub fn element_count<T: Plain>(bytes: &[u8]) -> Option<usize> {
    let size = size_of::<T>();
    bytes
        .len()
        .is_multiple_of(size)
        .then_some(bytes.len() / size)
}

/// Copies `bytes` into `values`; false (nothing copied) when the lengths differ.
pub fn copy_into<T: Plain>(values: &mut [T], bytes: &[u8]) -> bool {
    if std::mem::size_of_val(values) != bytes.len() {
        return false;
    }
    // SAFETY: as `slice_bytes`, mutably: any byte pattern written is a valid T (Plain), and the
    // lengths are equal.
    let target =
        unsafe { std::slice::from_raw_parts_mut(values.as_mut_ptr().cast::<u8>(), bytes.len()) };
    target.copy_from_slice(bytes);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_and_nodes_round_trip_through_their_bytes() {
        let header = FieldHeader {
            frame_id: 42,
            mesh_cols: 3,
            mesh_rows: 2,
            ..FieldHeader::default()
        };
        let back: FieldHeader = read_value(value_bytes(&header)).unwrap();
        assert_eq!(value_bytes(&back), value_bytes(&header));
        assert!(read_value::<FieldHeader>(&value_bytes(&header)[1..]).is_none());

        let nodes = [FieldNode::default(); 6];
        let bytes = slice_bytes(&nodes).to_vec();
        assert_eq!(element_count::<FieldNode>(&bytes), Some(6));
        assert_eq!(element_count::<FieldNode>(&bytes[1..]), None);
        let mut copied = [FieldNode::default(); 6];
        copied[2].u_px = 1.5;
        assert!(copy_into(&mut copied, &bytes));
        assert_eq!(slice_bytes(&copied), &bytes[..]);
        assert!(!copy_into(&mut copied[1..], &bytes));
    }

    #[test]
    fn pixels_are_their_little_endian_bytes() {
        assert_eq!(slice_bytes(&[0x0102u16, 0xa0b0]), [2, 1, 0xb0, 0xa0]);
    }
}
