//! A ParaView collection (`.pvd`): the per-frame `.vts` fields of a run or of `correlate` as
//! one time series, each file with its time, so that ParaView plays them against it (File >
//! Open the `.pvd`). Rewritten whole (atomically, by the caller) after each new file, so a run
//! that is killed leaves a collection of the files it wrote.

use std::fmt::Write as _;

/// The files of a collection, in the order written, each with its time step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Pvd {
    files: Vec<(String, f64)>,
}

impl Pvd {
    pub fn new() -> Pvd {
        Pvd::default()
    }

    /// Adds `file` (relative to the `.pvd`) at `time`: s since the run's start for a run, the
    /// image's index for `correlate` (images carry no time). A time that is not finite or not
    /// after the last one is refused (false): ParaView needs increasing time steps.
    pub fn push(&mut self, file: String, time: f64) -> bool {
        let increasing = self.files.last().is_none_or(|(_, last)| time > *last);
        if !(time.is_finite() && increasing) {
            return false;
        }
        self.files.push((file, time));
        true
    }

    pub fn len(&self) -> usize {
        self.files.len()
    }

    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The collection's XML.
    pub fn to_xml(&self) -> String {
        let mut text = String::from(
            "<?xml version=\"1.0\"?>\n\
             <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
             <Collection>\n",
        );
        for (file, time) in &self.files {
            let _ = writeln!(
                text,
                "<DataSet timestep=\"{time}\" group=\"\" part=\"0\" file=\"{}\"/>",
                escape(file)
            );
        }
        text.push_str("</Collection>\n</VTKFile>\n");
        text
    }
}

/// `text` as an XML attribute value.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_collection_is_xml_listing_each_file_with_increasing_times() {
        let mut pvd = Pvd::new();
        assert!(pvd.push("field_000010.vts".into(), 0.5));
        assert!(pvd.push("field_000020.vts".into(), 1.25));
        assert!(pvd.push("a&b \"c\".vts".into(), 2.0));
        // A time that does not increase is refused, the collection unchanged.
        assert!(!pvd.push("late.vts".into(), 2.0));
        assert!(!pvd.push("nan.vts".into(), f64::NAN));
        let xml = pvd.to_xml();
        let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
        assert_eq!(doc.root_element().attribute("type"), Some("Collection"));
        let sets: Vec<(String, f64)> = doc
            .descendants()
            .filter(|n| n.has_tag_name("DataSet"))
            .map(|n| {
                (
                    n.attribute("file").unwrap().to_string(),
                    n.attribute("timestep").unwrap().parse().unwrap(),
                )
            })
            .collect();
        assert_eq!(
            sets,
            [
                ("field_000010.vts".to_string(), 0.5),
                ("field_000020.vts".to_string(), 1.25),
                ("a&b \"c\".vts".to_string(), 2.0),
            ]
        );
    }
}
