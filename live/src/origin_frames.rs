//! The image the fields of the latest frame sequence are measured in (their origin frame), for
//! `strain_map.png`. The correlator's origin is the first frame *it* took of the sequence,
//! which a correlator behind the camera takes some frames after the first one: the first
//! [`FRAMES_KEPT`] frames of each sequence are copied until a field names its origin, then
//! only that one is kept.

use wire::FrameHeader;

/// Frames copied at the start of a sequence while no field has named its origin.
pub const FRAMES_KEPT: usize = 12;

#[derive(Debug, Default)]
pub struct OriginFrames {
    sequence_id: Option<u32>,
    frames: Vec<(FrameHeader, Vec<u16>)>,
    /// The origin a field named, when it was among the frames kept.
    chosen: Option<u64>,
    /// The origin a field named that was not among them.
    missed: Option<u64>,
}

impl OriginFrames {
    /// A frame seen on `frames` (its pixels copied only while the origin is unknown).
    pub fn on_frame(&mut self, header: &FrameHeader, pixels: &[u16]) {
        if self.sequence_id != Some(header.sequence_id) {
            *self = OriginFrames {
                sequence_id: Some(header.sequence_id),
                ..OriginFrames::default()
            };
        }
        if self.chosen.is_none()
            && self.missed.is_none()
            && self.frames.len() < FRAMES_KEPT
            && header.validate(pixels.len()).is_ok()
        {
            self.frames.push((*header, pixels.to_vec()));
        }
    }

    /// A field of sequence `sequence_id` measured from frame `origin_frame_id`.
    pub fn on_field(&mut self, sequence_id: u32, origin_frame_id: u64) {
        if self.sequence_id != Some(sequence_id) || self.chosen.is_some() || self.missed.is_some() {
            return;
        }
        match self
            .frames
            .iter()
            .position(|(h, _)| h.frame_id == origin_frame_id)
        {
            Some(i) => {
                let origin = self.frames.swap_remove(i);
                self.frames = vec![origin];
                self.chosen = Some(origin_frame_id);
            }
            None => {
                self.frames.clear();
                self.missed = Some(origin_frame_id);
            }
        }
    }

    /// The origin frame `frame_id`'s header and pixels, or why they are not kept.
    pub fn get(&self, frame_id: u64) -> Result<&(FrameHeader, Vec<u16>), String> {
        match (self.chosen, self.missed) {
            (Some(id), _) if id == frame_id => Ok(&self.frames[0]),
            (_, Some(id)) if id == frame_id => Err(format!(
                "its origin frame {id} was not among the first {FRAMES_KEPT} frames of its \
                 sequence the run saw (the correlator started that far behind the camera)"
            )),
            _ => Err(format!(
                "its origin frame {frame_id} is not the origin of the latest sequence's fields"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(id: u64, sequence_id: u32) -> FrameHeader {
        FrameHeader {
            frame_id: id,
            sequence_id,
            width_px: 2,
            height_px: 1,
            ..FrameHeader::default()
        }
    }

    #[test]
    fn the_origin_a_field_names_is_kept_even_when_it_is_not_the_first_frame() {
        let mut origins = OriginFrames::default();
        for id in 10..20 {
            origins.on_frame(&frame(id, 1), &[id as u16, 0]);
        }
        origins.on_field(1, 13);
        let (header, pixels) = origins.get(13).unwrap();
        assert_eq!((header.frame_id, pixels[0]), (13, 13));
        // Later fields and frames change nothing.
        origins.on_field(1, 14);
        origins.on_frame(&frame(20, 1), &[20, 0]);
        assert_eq!(origins.get(13).unwrap().0.frame_id, 13);
        assert!(origins.get(14).is_err());
    }

    #[test]
    fn an_origin_beyond_the_frames_kept_is_said_and_a_new_sequence_starts_afresh() {
        let mut origins = OriginFrames::default();
        for id in 0..(FRAMES_KEPT as u64 + 5) {
            origins.on_frame(&frame(id, 0), &[0, 0]);
        }
        origins.on_field(0, FRAMES_KEPT as u64 + 2);
        let why = origins.get(FRAMES_KEPT as u64 + 2).unwrap_err();
        assert!(why.contains("was not among the first 12 frames"), "{why}");
        origins.on_frame(&frame(100, 1), &[0, 0]);
        origins.on_field(1, 100);
        assert!(origins.get(100).is_ok());
        // A frame of the wrong size is not kept.
        origins.on_frame(&frame(200, 2), &[0]);
        origins.on_field(2, 200);
        assert!(origins.get(200).is_err());
    }
}
