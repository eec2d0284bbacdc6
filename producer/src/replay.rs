//! Replay of an image sequence (a folder, or a glob such as `dir/img_*.tif`) as a
//! [`FrameSource`]: natural order, every frame checked against the first one's size and depth.

use std::path::{Path, PathBuf};

use crate::error::ProducerError;
use crate::image_io::{decode_into, read_shape, ImageShape};
use crate::natural_sort::natural_cmp;
use crate::source::{check_buffer, FrameDims, FrameInfo, FrameSource};

/// File extensions replay reads (case-insensitive).
pub const IMAGE_EXTENSIONS: [&str; 4] = ["png", "tif", "tiff", "bmp"];

/// An ordered list of image files replayed one per frame.
#[derive(Debug)]
pub struct Replay {
    files: Vec<PathBuf>,
    shape: ImageShape,
    /// Position of the next file in `files`.
    next_index: usize,
    /// Frames given so far, over every pass (the `FrameInfo::index`).
    frames_given: u64,
    /// Starts again from the first file after the last one, endlessly.
    looping: bool,
    scratch: Vec<u8>,
}

impl Replay {
    /// Lists and checks a sequence. `source` is a folder (every .png/.tif/.tiff/.bmp inside,
    /// other files ignored) or a glob whose last component holds `*` or `?`.
    /// Every file's header is read now: a non-image, another size or another depth is an error
    /// naming the file. Pixel data are decoded frame by frame (a truncated file fails then).
    pub fn open(source: impl AsRef<Path>) -> Result<Self, ProducerError> {
        let files = list_images(source.as_ref())?;
        let first = files
            .first()
            .expect("list_images returns at least one file");
        let shape = read_shape(first)?;
        for file in &files[1..] {
            let other = read_shape(file)?;
            if other != shape {
                return Err(ProducerError::FrameMismatch {
                    path: file.clone(),
                    first: first.clone(),
                    found_width: other.width,
                    found_height: other.height,
                    found_bit_depth: other.bit_depth,
                    expected_width: shape.width,
                    expected_height: shape.height,
                    expected_bit_depth: shape.bit_depth,
                });
            }
        }
        Ok(Self {
            files,
            shape,
            next_index: 0,
            frames_given: 0,
            looping: false,
            scratch: Vec::with_capacity(shape.len_px() * 2),
        })
    }

    /// The files, in replay order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// Starts again from the first file.
    pub fn rewind(&mut self) {
        self.next_index = 0;
    }

    /// With `looping`, the sequence starts again from the first file after the last one and
    /// never ends (`frames_total` is then `None`); frame indices keep counting up.
    pub fn set_looping(&mut self, looping: bool) {
        self.looping = looping;
    }
}

impl FrameSource for Replay {
    fn dims(&self) -> FrameDims {
        FrameDims {
            width: self.shape.width,
            height: self.shape.height,
            bit_depth: self.shape.bit_depth,
        }
    }

    fn frames_total(&self) -> Option<u64> {
        (!self.looping).then_some(self.files.len() as u64)
    }

    fn next_frame(&mut self, out: &mut [u16]) -> Result<Option<FrameInfo>, ProducerError> {
        check_buffer(self.dims(), out)?;
        if self.looping && self.next_index >= self.files.len() {
            self.rewind();
        }
        let Some(file) = self.files.get(self.next_index) else {
            return Ok(None);
        };
        let read = match decode_into(file, &mut self.scratch, out) {
            // A file rewritten with another size since the list was read: the same message
            // as any other frame of another shape.
            Err(ProducerError::ImageSize {
                found_width,
                found_height,
                found_bit_depth,
                ..
            }) => ImageShape {
                width: found_width,
                height: found_height,
                bit_depth: found_bit_depth,
            },
            other => other?,
        };
        if read != self.shape {
            return Err(ProducerError::FrameMismatch {
                path: file.clone(),
                first: self.files[0].clone(),
                found_width: read.width,
                found_height: read.height,
                found_bit_depth: read.bit_depth,
                expected_width: self.shape.width,
                expected_height: self.shape.height,
                expected_bit_depth: self.shape.bit_depth,
            });
        }
        let index = self.frames_given;
        self.next_index += 1;
        self.frames_given += 1;
        Ok(Some(FrameInfo {
            index,
            truth: None,
            rig_sample_id: None,
            sequence_id: 0,
        }))
    }
}

fn has_image_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| IMAGE_EXTENSIONS.iter().any(|k| e.eq_ignore_ascii_case(k)))
}

/// Lists the image files of a folder or glob in natural order; never empty on success.
pub fn list_images(source: &Path) -> Result<Vec<PathBuf>, ProducerError> {
    let name = source.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let is_glob = name.contains('*') || name.contains('?');
    let (dir, pattern) = if is_glob {
        let parent = source.parent().filter(|p| !p.as_os_str().is_empty());
        (parent.unwrap_or(Path::new(".")).to_path_buf(), Some(name))
    } else {
        (source.to_path_buf(), None)
    };
    let entries = std::fs::read_dir(&dir).map_err(|e| ProducerError::Io {
        path: dir.clone(),
        reason: e,
    })?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| ProducerError::Io {
            path: dir.clone(),
            reason: e,
        })?;
        let path = entry.path();
        if !path.is_file() {
            continue;
        }
        let file_name = entry.file_name();
        let Some(file_name) = file_name.to_str() else {
            continue;
        };
        let selected = match pattern {
            Some(p) => wildcard_match(p.as_bytes(), file_name.as_bytes()),
            None => has_image_extension(&path),
        };
        if selected {
            files.push(path);
        }
    }
    if files.is_empty() {
        return Err(ProducerError::NoImages {
            path: source.to_path_buf(),
        });
    }
    files.sort_by(|a, b| {
        let a = a.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let b = b.file_name().and_then(|n| n.to_str()).unwrap_or("");
        natural_cmp(a, b)
    });
    Ok(files)
}

/// Matches `*` (any run) and `?` (one byte); iterative with one backtrack point, so linear-ish
/// and bounded by `pattern.len() * text.len()` steps.
fn wildcard_match(pattern: &[u8], text: &[u8]) -> bool {
    let (mut p, mut t) = (0usize, 0usize);
    let mut star: Option<(usize, usize)> = None;
    while t < text.len() {
        if p < pattern.len() && (pattern[p] == b'?' || pattern[p] == text[t]) {
            p += 1;
            t += 1;
        } else if p < pattern.len() && pattern[p] == b'*' {
            star = Some((p, t));
            p += 1;
        } else if let Some((sp, st)) = star {
            p = sp + 1;
            t = st + 1;
            star = Some((sp, st + 1));
        } else {
            return false;
        }
    }
    pattern[p..].iter().all(|&c| c == b'*')
}

#[cfg(test)]
mod tests {
    use super::wildcard_match;

    #[test]
    fn wildcard() {
        assert!(wildcard_match(b"img_*.tif", b"img_001.tif"));
        assert!(wildcard_match(b"*", b"a"));
        assert!(wildcard_match(b"a?c", b"abc"));
        assert!(!wildcard_match(b"img_*.tif", b"img_001.png"));
        assert!(!wildcard_match(b"a?c", b"ac"));
    }
}
