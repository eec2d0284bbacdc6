//! `dicstream run --print-config`: the defaults, written by the configuration's own types (so
//! a key, its spelling and its default cannot drift from what is read), with the comment of
//! each key from [`COMMENTS`]. A test checks that every key written has its comment and every
//! comment its key.

use super::RunConfig;
use std::fmt::Write as _;

/// The comment written above a key (`section.key`) or a table (`[section]`).
const COMMENTS: &[(&str, &str)] = &[
    ("[run]", ""),
    ("run.results_dir", "Parent folder of the per-run results folders (<results_dir>/<date-time>/)."),
    ("run.restart", "Restart a process that dies (at most max_restarts times each)."),
    ("run.max_restarts", ""),
    ("run.fields_every", "Keep the field of every Nth correlated frame (fields/field_<frame>.csv, and .vtk)."),
    ("run.vtk", ""),
    ("run.status_interval_s", "Seconds between two status lines, and given to a process to stop before SIGKILL."),
    ("run.stop_timeout_s", ""),
    ("run.stale_after_s", "Seconds after which a stopped (SIGSTOP) or silent process is killed as hung."),
    ("run.dashboard", "The live dashboard (ADDR:PORT, or \"off\"); a non-loopback address serves other\nmachines too."),
    ("run.processes", "The processes of the bench this host's run starts: rig, producer, correlator,\nidentifier (all four); on two hosts linked by [link], each host's part (docs/link.md)."),
    ("run.map_range", "Colour range of strain_map.png: auto (the 2nd-98th percentile, at least 30 times\nthe field's own noise wide), symmetric (about zero) or LO:HI (e.g. -0.01:0.05)."),
    ("[camera]", "The simulated camera renders the specimen as the rig deforms it."),
    ("camera.width_px", ""),
    ("camera.height_px", ""),
    ("camera.fps", ""),
    ("camera.bit_depth", "8, 10, 12 or 16 bit."),
    ("camera.mm_per_px", "Image scale of the specimen, mm per px: 256 mm across a 1024 px image, the\ncruciform's central square, fillets and the roots of its four arms (the field\nroute integrates forces through cuts across them)."),
    ("camera.strip_mm_per_px", "The scale when a finite-element strip is mounted (uniaxial tests on a\nstructure; the camera is re-framed on it): the 100 mm strip and its clamps."),
    ("camera.scale_mm_per_px", "The fields' scale, mm per px, for their mm columns (x_mm,y_mm,u_mm,v_mm): 0 =\nthe simulated camera's own (mm_per_px, strip_mm_per_px), none for a real camera\n(px only). Or from a known length: two image points (px) and the distance\nbetween them on the specimen (mm), \"X1,Y1 X2,Y2 MM\" (give one of the two)."),
    ("camera.scale_known_length", ""),
    ("camera.speckle_size_px", "Speckle spot size (FWHM), px; seed of the pattern and the noise."),
    ("camera.seed", ""),
    ("camera.threads", "Rendering threads (the correlator wants the cores more)."),
    ("camera.source", "Where frames come from: simulated (rendered from the simulated rig, with ground\ntruth), watch (images another program writes into watch_dir), replay (the\nimages of replay_files at fps) or genicam (a GenICam camera: a build with the\ngenicam feature). Real images have no ground truth: no truth columns, no\nacceptance. width_px/height_px must then be the images' size."),
    ("camera.watch_dir", ""),
    ("camera.watch_from_start", ""),
    ("camera.watch_idle_timeout_s", "0: the camera never ends by itself."),
    ("camera.watch_settle_ms", ""),
    ("camera.replay_files", ""),
    ("camera.genicam_id", "genicam_id \"\" = the first camera; genicam_exposure_us, genicam_gain_db when set;\npixel format Mono8/10/12/16 (or packed Mono10p/Mono12p/Mono12Packed), roi\n\"x,y,w,h\", trigger software/hardware/free (\"\" = as the camera is)."),
    ("camera.genicam_pixel_format", ""),
    ("camera.genicam_roi", ""),
    ("camera.genicam_trigger", ""),
    ("[correlator]", ""),
    ("correlator.method", "Sub-pixel method: correli (the paper; the default, the fastest), icgn1 (inverse\ncompositional Gauss-Newton, affine subsets: less noise, several times slower),\nicgn2 (second-order subsets) or icgn (the order chosen per node: second order where\nthe field's curvature biases the first)."),
    ("correlator.zoi_px", "ZOI (subset) side px (any size from 9 for the IC-GN methods, 2^s for correli) and\ndistance between ZOI centres px (paper section 3.b)."),
    ("correlator.step_px", ""),
    ("correlator.threads", ""),
    ("correlator.strain", "Node strain measure: log (m = 0), green (m = 1), nominal (m = 1/2) or small."),
    ("correlator.reference", "Reference: fixed, incremental (consecutive frames) or auto (renewed when the\ncorrelation degrades: the ZOIs' deformation since the reference, the score or\nthe nodes refused; never for a rigid motion; mesh followed)."),
    ("correlator.guess", "Initial guess per ZOI: auto (previous field or significant global (U0, V0),\nfailed nodes grown from verified neighbours, keypoints when too few verify),\npredict (previous field, neighbours) or correli (paper)."),
    ("correlator.min_zncc", "A node is ok only when the ZNCC of its reference ZOI with the frame, sampled at\nits displacement and local gradient, reaches this (0 < min_zncc < 1)."),
    ("correlator.gradient_correction", "Remove, to first order, the rigid ZOI's bias under a displacement gradient\n(beyond the paper; false = CORRELI-GD as published)."),
    ("correlator.gauges", "Virtual gauges placed in the first frame's image (px), read on every field into\nframes.csv: \"NAME=rect:X,Y,W,H\" or \"NAME=polygon:x,y x,y x,y ...\" (a strain\ngauge: the mean strain of the valid nodes inside), \"NAME=extensometer:x,y x,y\"\n(the two points followed; their elongation)."),
    ("correlator.control_gauge", "The gauge the fields carry, the one strain control closes its loop on and the\nidentifier's gauge route reads: centre (the mesh's central half), all (every\nvalid node) or the name of a rect or polygon gauge."),
    ("[correlator.region]", "Where the correlator measures. A node is measured only when its whole ZOI lies\ninside the region; the others are outside_region in every field (not failed;\nleft out of the gauge and the strain fits). mask = \"FILE.png\" when set: an image\nthe camera's size, non-zero pixels measured (relative to the run's folder)."),
    ("correlator.region.roi", "margin (the whole image less half a ZOI on each side: a border node can move\nby the integer search's reach before its ZOI leaves the image), centred-pow2\n(the paper's largest centred 2^p square) or \"x,y,w,h\" px."),
    ("correlator.region.polygons", "Polygons in image px, each \"x,y x,y x,y ...\" (at least 3 vertices, not\ncrossing itself, inside the image); their union, within roi and mask."),
    ("[rig]", ""),
    ("rig.speed", "Simulated time per wall time; rig/state and rig.csv rates, Hz of simulated time."),
    ("rig.publish_hz", ""),
    ("rig.log_hz", ""),
    ("rig.seed", ""),
    ("rig.source", "simulated (the campaign below) or csv-follow (a test machine's CSV log, [rig.csv])."),
    ("[[rig.tests]]", "The campaign, in order: each test mounts its specimen (uniaxial: a 100 x 20 x 2 mm\nstrip; equibiaxial: a 100 x 100 x 2 mm cruciform centre), ramps the elongation to\n`stretch` at `rate_per_s` in centroid control, holds, unloads. A test alone may\ninstead be strain-controlled (the correlator's fields close the loop):\ncontrol = \"strain\", kind = uniaxial | equibiaxial | pure_shear | biaxial,\nratio = ln(ly)/ln(lx) (biaxial), stretch = the larger measured stretch,\nrate_per_s = log strain rate; stale_s = 0.6, min_valid_nodes = 16,\non_interlock = \"resume\" | \"stop\"."),
    ("rig.tests.kind", ""),
    ("rig.tests.stretch", ""),
    ("rig.tests.rate_per_s", ""),
    ("[rig.csv]", ""),
    ("rig.csv.file", "The CSV a test machine's software appends to (waited for if missing; a partial\nlast line waits for its newline; a malformed line is reported and skipped)."),
    ("rig.csv.time_column", "Column names as in the header, without their unit (\"\" = not logged)."),
    ("rig.csv.force_x_column", ""),
    ("rig.csv.force_y_column", ""),
    ("rig.csv.force_z_column", ""),
    ("rig.csv.displacement_x_column", ""),
    ("rig.csv.displacement_y_column", ""),
    ("rig.csv.displacement_z_column", ""),
    ("rig.csv.time_unit", "Units: s/ms/min, N/kN, mm/um/m; \"\" = as the header says (`Fx (kN)`)."),
    ("rig.csv.force_unit", ""),
    ("rig.csv.displacement_unit", ""),
    ("rig.csv.delimiter", "\",\", \";\" or \"tab\"; cells may be quoted, a comma in a cell is a decimal comma."),
    ("rig.csv.offset_s", "Seconds added to the machine's time to put it on the camera's."),
    ("rig.csv.section_x_mm2", "Initial specimen sections normal to X and Y, mm² (stress = force / section)."),
    ("rig.csv.section_y_mm2", ""),
    ("rig.csv.idle_timeout_s", "The test is over after this long without a new row."),
    ("[specimen]", ""),
    ("specimen.law_f", "Material of the specimens: ln f(I1) = sum a_i (I1 - 3)^i and\nln g(I2) = sum b_i (I2 - 3)^i (eqs. 22, 25; f, g in MPa). Default: Smactane,\nTables 3 and 4 (n = 2). A virtual test must give them back."),
    ("specimen.law_g", ""),
    ("specimen.model", "The rig's specimen: structure (the finite-element cruciform and strip below: grip\nand edge effects from the mechanics; the run's verdict is the law the field route\nidentifies from the cruciform's whole field) or homogeneous (the analytic sheet,\nlambda = the grips' nominal stretch; the verdict is the gauge route's law, from\nforces over current sections, right only for a homogeneous field)."),
    ("[specimen.geometry]", "The specimen as a finite-element structure (`dicstream specimen` solves it, and the\nrig with model = \"structure\"): cruciform, uniaxial_strip or plane_strain_strip,\neach shape's geometry in its table below (mm). The strips are pulled along x; a\nstrip's table is all or nothing."),
    ("specimen.geometry.shape", ""),
    ("[specimen.geometry.cruciform]", "A central square of side arm_width_mm, four arms of that width and free length\narm_length_mm to their grips, fillets at the re-entrant corners, optional slits\nfrom each grip; element_size_mm is the target element edge (T6 elements)."),
    ("specimen.geometry.cruciform.arm_width_mm", ""),
    ("specimen.geometry.cruciform.arm_length_mm", ""),
    ("specimen.geometry.cruciform.fillet_radius_mm", ""),
    ("specimen.geometry.cruciform.slits_per_arm", ""),
    ("specimen.geometry.cruciform.slit_length_mm", ""),
    ("specimen.geometry.cruciform.thickness_mm", ""),
    ("specimen.geometry.cruciform.element_size_mm", ""),
    ("[specimen.geometry.uniaxial_strip]", "length_mm between the clamps (along x), width_mm across."),
    ("specimen.geometry.uniaxial_strip.length_mm", ""),
    ("specimen.geometry.uniaxial_strip.width_mm", ""),
    ("specimen.geometry.uniaxial_strip.thickness_mm", ""),
    ("specimen.geometry.uniaxial_strip.element_size_mm", ""),
    ("[specimen.geometry.plane_strain_strip]", "Fig. 9's wide strip: short between the clamps, wide across."),
    ("specimen.geometry.plane_strain_strip.length_mm", ""),
    ("specimen.geometry.plane_strain_strip.width_mm", ""),
    ("specimen.geometry.plane_strain_strip.thickness_mm", ""),
    ("specimen.geometry.plane_strain_strip.element_size_mm", ""),
    ("[identifier]", ""),
    ("identifier.models", "Models ranked at each refit (see `dicstream identify --help`), or all."),
    ("identifier.route", "gauge (the gauge's averages), field (the whole field of the cruciform by the\nvirtual fields method; needs [specimen] model = \"structure\" and a view that\ncrosses the arms: [camera] mm_per_px), both, or auto (both on a structure)."),
    ("identifier.plot_all_models", "f_I1.png and g_I2.png: every ranked model's curve, not only the identified\n(best-ranked) law's, against the route's points."),
];

const PREAMBLE: &str =
    "# dicstream run configuration. Every key is optional: a missing key takes the value\n\
                        # shown here. Unknown keys are refused.\n";

/// What a line of the written TOML opens: a table (`[rig.csv]`, `[[rig.tests]]`) or a key
/// (`rig.csv.file`), with the table it is in.
fn entry_of(line: &str, table: &str) -> Option<String> {
    let line = line.trim();
    if line.starts_with('[') {
        return Some(line.to_string());
    }
    let key = line.split_once(" = ")?.0.trim();
    Some(format!("{table}.{key}"))
}

/// The table a header line names (`[[rig.tests]]` → `rig.tests`).
fn table_of(header: &str) -> String {
    header.trim_matches(|c| c == '[' || c == ']').to_string()
}

fn comment(entry: &str) -> Option<&'static str> {
    COMMENTS.iter().find(|(e, _)| *e == entry).map(|(_, c)| *c)
}

/// The non-blank lines of a written configuration, each with what it opens (`entry_of`),
/// following the tables.
fn entries(toml: &str) -> Vec<(&str, Option<String>)> {
    let mut table = String::new();
    let mut out = Vec::new();
    for line in toml.lines().filter(|l| !l.trim().is_empty()) {
        let entry = entry_of(line, &table);
        if line.trim_start().starts_with('[') {
            table = table_of(line);
        }
        out.push((line, entry));
    }
    out
}

impl RunConfig {
    /// The defaults as a commented TOML file to start from. Each comment is written once, above
    /// the first occurrence of its key or table; the TOML's own blank lines are left out and
    /// one blank line goes before each table.
    pub fn commented_defaults() -> String {
        let mut out = String::from(PREAMBLE);
        let mut said: Vec<String> = Vec::new();
        for (line, entry) in entries(&RunConfig::default().to_toml()) {
            if let Some(entry) = entry {
                if line.trim_start().starts_with('[') {
                    let _ = writeln!(out);
                }
                if !said.contains(&entry) {
                    for text in comment(&entry).unwrap_or("").lines() {
                        let _ = writeln!(out, "# {text}");
                    }
                    said.push(entry);
                }
            }
            let _ = writeln!(out, "{line}");
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every entry the defaults write (optional keys that are absent by default are not
    /// written: their comment is their neighbour's).
    fn written_entries() -> Vec<String> {
        let mut written: Vec<String> = Vec::new();
        for (_, entry) in entries(&RunConfig::default().to_toml()) {
            if let Some(entry) = entry.filter(|e| !written.contains(e)) {
                written.push(entry);
            }
        }
        written
    }

    #[test]
    fn every_key_written_has_its_comment_and_every_comment_its_key() {
        let written = written_entries();
        for entry in &written {
            assert!(comment(entry).is_some(), "no comment for {entry}");
        }
        for (entry, _) in COMMENTS {
            assert!(written.iter().any(|w| w == entry), "{entry} is not a key");
        }
    }

    #[test]
    fn the_commented_defaults_parse_back_to_the_defaults() {
        let text = RunConfig::commented_defaults();
        assert!(text.contains("# Sub-pixel method: correli"), "{text}");
        let parsed = RunConfig::from_toml(&text, "defaults").unwrap();
        assert_eq!(parsed, RunConfig::default());
    }
}
