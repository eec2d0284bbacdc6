//! `dicstream correlate` end to end: the files other tools read (field_NNNN.csv with its header,
//! summary.json with its keys, --vtk, --png) and the bad inputs of issue 3 (unreadable file,
//! images of different sizes, non-power-of-two ZOI, step 0, ZOI larger than the ROI, a flat
//! image), each a clear message or a per-node status, never a crash or a NaN.

use crate::common;
use crate::common::dicstream;

use common::camera::{render, translation, unrelated_speckle};
use std::path::{Path, PathBuf};

const W: usize = 192;
const H: usize = 160;

/// A folder removed when the test ends, passed or failed.
struct TempDir(PathBuf);

impl TempDir {
    fn new(label: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("offline_{}_{label}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn write_png(path: &Path, pixels: &[u16], width: usize, height: usize) {
    let dims = producer::FrameDims {
        width: width as u32,
        height: height as u32,
        bit_depth: 16,
    };
    producer::write_frame(
        path,
        dims,
        pixels,
        producer::ImageFormatOut::Png16,
        &mut Vec::new(),
    )
    .unwrap();
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Correlates `ref.png` against two translated images into `out` with `extra` arguments.
fn correlate_two(dir: &TempDir, out: &str, extra: &[&str]) -> (std::process::Output, PathBuf) {
    let reference = dir.0.join("ref.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let mut args = vec!["correlate".to_string(), path(&reference).to_string()];
    for (k, (u, v)) in [(0.4, 0.0), (0.8, -0.2)].into_iter().enumerate() {
        let file = dir.0.join(format!("def_{k}.png"));
        write_png(
            &file,
            &render(W, H, &translation(u, v).0, 2 + k as u64),
            W,
            H,
        );
        args.push(path(&file).to_string());
    }
    let out = dir.0.join(out);
    args.extend(["--zoi", "32", "--step", "16", "--out", path(&out)].map(String::from));
    args.extend(extra.iter().map(|a| a.to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    (dicstream(&args), out)
}

#[test]
fn a_scale_gives_mm_columns_units_json_says_each_unit_and_the_pvd_lists_the_vts_files() {
    let dir = TempDir::new("scale");
    // 0,0 to 300,400 px is 500 px: 125 mm is 0.25 mm per px, as given directly.
    let (known, out_known) = correlate_two(
        &dir,
        "known",
        &["--known-length", "0,0 300,400 125", "--vtk"],
    );
    assert!(
        known.status.success(),
        "{}",
        String::from_utf8_lossy(&known.stderr)
    );
    let (direct, out_direct) = correlate_two(&dir, "direct", &["--mm-per-px", "0.25"]);
    assert!(
        direct.status.success(),
        "{}",
        String::from_utf8_lossy(&direct.stderr)
    );
    let field = |out: &Path| std::fs::read_to_string(out.join("field_0001.csv")).unwrap();
    assert_eq!(field(&out_known), field(&out_direct));
    let csv = field(&out_known);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(&header[14..], ["x_mm", "y_mm", "u_mm", "v_mm"]);
    for line in csv.lines().skip(1) {
        let row: Vec<f64> = line
            .split(',')
            .enumerate()
            .filter(|(k, _)| *k != 9)
            .map(|(_, c)| c.parse().unwrap())
            .collect();
        // u_mm = 0.25 u (the status column left out: u is row[2], u_mm row[15]).
        assert!((row[15] - 0.25 * row[2]).abs() < 1e-5, "{line}");
        assert!((row[13] - 0.25 * row[0]).abs() < 1e-5, "{line}");
    }
    // units.json names every column of the header with its unit, and the strain measure.
    let units: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_known.join("units.json")).unwrap())
            .unwrap();
    let fields = &units["files"]["field_*.csv"];
    let names: Vec<&str> = fields["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, header);
    assert_eq!(fields["columns"][2]["unit"], "px");
    assert_eq!(fields["columns"][16]["unit"], "mm");
    assert!(fields["columns"][6]["meaning"]
        .as_str()
        .unwrap()
        .contains("tensor component"));
    let notes = fields["notes"].to_string();
    assert!(
        notes.contains("strain measure: log") && notes.contains("0.25 mm per px"),
        "{notes}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_known.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["settings"]["mm_per_px"], 0.25);
    // The collection lists each .vts with increasing time steps, and each is XML.
    let pvd = std::fs::read_to_string(out_known.join("fields.pvd")).unwrap();
    let doc = roxmltree::Document::parse(&pvd).unwrap();
    let sets: Vec<(String, f64)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|n| {
            let time = n.attribute("timestep").unwrap().parse().unwrap();
            (n.attribute("file").unwrap().to_string(), time)
        })
        .collect();
    assert_eq!(
        sets,
        [
            ("field_0001.vts".to_string(), 1.0),
            ("field_0002.vts".to_string(), 2.0)
        ]
    );
    for (file, _) in &sets {
        let vts = std::fs::read_to_string(out_known.join(file)).unwrap();
        roxmltree::Document::parse(&vts).unwrap();
        assert!(vts.contains("Name=\"displacement_mm\""));
    }
    // Without a scale: px only.
    let (plain, out_plain) = correlate_two(&dir, "plain", &[]);
    assert!(plain.status.success());
    assert!(field(&out_plain)
        .starts_with("x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy\n"));
    let units = std::fs::read_to_string(out_plain.join("units.json")).unwrap();
    assert!(
        units.contains("no scale known") && !units.contains("\"mm\""),
        "{units}"
    );
}

#[test]
fn a_bad_scale_is_refused_with_its_reason() {
    let dir = TempDir::new("bad_scale");
    for (args, expected) in [
        (
            ["--known-length", "5,5 5,5 10"],
            "the two points are the same",
        ),
        (
            ["--known-length", "0,0 10,0 0"],
            "expected a distance above 0 mm",
        ),
        (["--known-length", "0,0 NaN,0 10"], "x2 is NaN"),
        (["--mm-per-px", "0"], "expected a finite number above 0"),
    ] {
        let (output, _) = correlate_two(&dir, "out", &args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains(expected),
            "{args:?}: {stderr}"
        );
    }
    let (both, _) = correlate_two(
        &dir,
        "out",
        &["--mm-per-px", "0.2", "--known-length", "0,0 10,0 1"],
    );
    assert!(
        !both.status.success(),
        "{}",
        String::from_utf8_lossy(&both.stderr)
    );
}

#[test]
fn figure_ranges_are_obeyed_and_bad_ones_refused() {
    let dir = TempDir::new("ranges");
    for (range, expected) in [
        ("0.2:0.1", "LO 0.2 is not below HI 0.1"),
        ("NaN:1", "LO NaN is not finite"),
        ("0.1:0.1", "is not below"),
        ("wide", "neither a word nor LO:HI"),
    ] {
        let (output, _) = correlate_two(&dir, "out", &["--png", "--range", range]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            !output.status.success() && stderr.contains(expected),
            "{range}: {stderr}"
        );
    }
    // A fixed range: the bar's ends are its values, whatever the field.
    let (output, out) = correlate_two(&dir, "fixed", &["--png", "--range", "-2:2"]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["settings"]["figure_range"], "-2:2");
    // u 0.4 px on a range of -2 to 2 px, centred on zero: pale red, red above blue.
    let png = image::open(out.join("u_0001.png")).unwrap().to_rgb8();
    let centre = png.get_pixel(12 + W as u32 / 2, 44 + H as u32 / 2).0;
    let grey = image::open(out.join("v_0001.png")).unwrap().to_rgb8();
    let v_centre = grey.get_pixel(12 + W as u32 / 2, 44 + H as u32 / 2).0;
    assert!(centre[0] > centre[2], "u > 0 reddish: {centre:?}");
    assert!(
        (v_centre[0] as i32 - v_centre[2] as i32).abs() < (centre[0] as i32 - centre[2] as i32),
        "v 0 nearer white than u 0.4: {v_centre:?} {centre:?}"
    );
}

#[test]
fn fields_and_summary_follow_the_contract() {
    let dir = TempDir::new("contract");
    let shifts = [(0.3, -0.2), (0.75, 0.45)];
    let reference = dir.0.join("ref.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let mut deformed = Vec::new();
    for (k, &(u, v)) in shifts.iter().enumerate() {
        let file = dir.0.join(format!("def_{k}.png"));
        write_png(
            &file,
            &render(W, H, &translation(u, v).0, 2 + k as u64),
            W,
            H,
        );
        deformed.push(file);
    }
    let out = dir.0.join("out");
    let output = dicstream(&[
        "correlate",
        path(&reference),
        path(&deformed[0]),
        path(&deformed[1]),
        "--zoi",
        "32",
        "--step",
        "16",
        "--out",
        path(&out),
        "--vtk",
        "--png",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    // Not a terminal: no progress bar.
    assert!(!stderr.contains("frames,"), "{stderr}");
    for (k, &(u, v)) in shifts.iter().enumerate() {
        let index = k + 1;
        let csv = std::fs::read_to_string(out.join(format!("field_{index:04}.csv"))).unwrap();
        let mut lines = csv.lines();
        assert_eq!(
            lines.next(),
            Some("x,y,u,v,exx,eyy,exy,score,iterations,status,du_dx,du_dy,dv_dx,dv_dy")
        );
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert!(!rows.is_empty());
        let (mut su, mut sv) = (0.0, 0.0);
        for row in &rows {
            assert_eq!(row.len(), 14, "{row:?}");
            let numbers: Vec<f64> = row[..9].iter().map(|v| v.parse().unwrap()).collect();
            assert!(numbers.iter().all(|v| v.is_finite()));
            assert_eq!(row[9], "ok", "{row:?}");
            // A translation: the neighbours' least-squares gradient (correli) is about zero.
            let gradient: Vec<f64> = row[10..].iter().map(|v| v.parse().unwrap()).collect();
            assert!(gradient.iter().all(|g| g.abs() < 0.01), "{row:?}");
            su += numbers[2];
            sv += numbers[3];
        }
        let (mu, mv) = (su / rows.len() as f64, sv / rows.len() as f64);
        eprintln!(
            "field_{index:04}.csv: {} nodes, mean u {mu:+.4} v {mv:+.4} (truth {u:+.2} {v:+.2})",
            rows.len()
        );
        assert!((mu - u).abs() < 0.01 && (mv - v).abs() < 0.01);
        let vtk = std::fs::read_to_string(out.join(format!("field_{index:04}.vtk"))).unwrap();
        assert!(vtk.starts_with("# vtk DataFile Version 3.0"));
        assert!(vtk.contains("VECTORS displacement_px double"));
        // Each quantity's figure: the image under its title, beside its colour bar.
        for map in ["u", "v", "exx", "eyy", "exy"] {
            let png = producer::read_image(out.join(format!("{map}_{index:04}.png"))).unwrap();
            assert!(
                png.width as usize > W + 100 && png.height as usize > H + 40,
                "{map}: {} x {}",
                png.width,
                png.height
            );
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let frames = summary["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame["index"], k + 1);
        assert_eq!(frame["file"], path(&deformed[k]));
        assert_eq!(frame["nodes"], frame["valid"]);
        assert!((frame["u_mean"].as_f64().unwrap() - shifts[k].0).abs() < 0.01);
        assert!((frame["v_mean"].as_f64().unwrap() - shifts[k].1).abs() < 0.01);
        for measure in ["small", "green", "nominal", "log"] {
            for component in ["exx", "eyy", "exy"] {
                let value = frame["gauge"][measure][component].as_f64().unwrap();
                assert!(value.abs() < 5e-4, "{measure} {component} {value}");
            }
        }
        assert!(frame["elapsed_ms"].as_f64().unwrap() > 0.0);
    }
    let settings = &summary["settings"];
    assert_eq!(settings["zoi"], 32);
    assert_eq!(settings["step"], 16);
    assert_eq!(settings["strain"], "log");
    // No temporary file left behind by the atomic writes.
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// `--method icgn1` takes an odd subset (the summary says which method ran, nodes sit on
/// pixels); `--method correli` refuses it and points to IC-GN.
#[test]
fn method_icgn1_takes_any_subset_size() {
    let dir = TempDir::new("method");
    let (u, v) = (0.41, -0.27);
    let reference = dir.0.join("ref.png");
    let deformed = dir.0.join("def.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    write_png(&deformed, &render(W, H, &translation(u, v).0, 2), W, H);
    let out = dir.0.join("out");
    let run = |method: &str| {
        dicstream(&[
            "correlate",
            path(&reference),
            path(&deformed),
            "--method",
            method,
            "--zoi",
            "33",
            "--out",
            path(&out),
        ])
    };
    let output = run("icgn1");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["settings"]["method"], "icgn1");
    assert_eq!(summary["settings"]["zoi"], 33);
    let frame = &summary["frames"][0];
    assert_eq!(frame["nodes"], frame["valid"]);
    assert!(
        (frame["u_mean"].as_f64().unwrap() - u).abs() < 0.01,
        "{frame}"
    );
    assert!(
        (frame["v_mean"].as_f64().unwrap() - v).abs() < 0.01,
        "{frame}"
    );
    let csv = std::fs::read_to_string(out.join("field_0001.csv")).unwrap();
    let x: f64 = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(x.fract(), 0.0, "an odd subset is centred on a pixel: {x}");
    let output = run("correli");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(
        stderr.contains("not a power of two") && stderr.contains("--method icgn1"),
        "{stderr}"
    );
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = TempDir::new("bad");
    let reference = dir.0.join("ref.png");
    let image = render(W, H, &translation(0.0, 0.0).0, 1);
    write_png(&reference, &image, W, H);
    let out = dir.0.join("out");
    let refused = |args: &[&str], needle: &str| {
        let output = dicstream(args);
        let stderr = String::from_utf8_lossy(&output.stderr).to_string();
        eprintln!("{args:?}\n  -> {}", stderr.trim());
        assert!(!output.status.success(), "{args:?} must fail");
        assert_eq!(
            output.status.code(),
            Some(1),
            "an error, not a crash: {stderr}"
        );
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
    };
    // An unreadable file: named in the message.
    let garbage = dir.0.join("garbage.png");
    std::fs::write(&garbage, b"this is not a PNG").unwrap();
    refused(
        &[
            "correlate",
            path(&reference),
            path(&garbage),
            "--out",
            path(&out),
        ],
        "garbage.png",
    );
    let missing = dir.0.join("missing.tif");
    refused(
        &[
            "correlate",
            path(&reference),
            path(&missing),
            "--out",
            path(&out),
        ],
        "missing.tif",
    );
    let output = dicstream(&[
        "correlate",
        path(&reference),
        path(&missing),
        "--out",
        path(&out),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(
        stderr.matches("os error 2").count(),
        1,
        "cause printed once: {stderr}"
    );
    // Images of different sizes.
    let small = dir.0.join("small.png");
    write_png(
        &small,
        &render(W / 2, H, &translation(0.0, 0.0).0, 2),
        W / 2,
        H,
    );
    refused(
        &[
            "correlate",
            path(&reference),
            path(&small),
            "--out",
            path(&out),
        ],
        "expected 192x160 px like the reference",
    );
    // A non-power-of-two ZOI: refused with the nearest power of two.
    refused(
        &[
            "correlate",
            path(&reference),
            path(&reference),
            "--zoi",
            "30",
            "--out",
            path(&out),
        ],
        "use 32 px",
    );
    // Step 0.
    refused(
        &[
            "correlate",
            path(&reference),
            path(&reference),
            "--step",
            "0",
            "--out",
            path(&out),
        ],
        "step 0 px is invalid",
    );
    // A ROI beyond the image, said as the user wrote it (not a Rust struct).
    refused(
        &[
            "correlate",
            path(&reference),
            path(&reference),
            "--roi",
            "500,500,100,100",
            "--out",
            path(&out),
        ],
        "ROI 500,500,100,100 (x,y,width,height) does not fit",
    );
    // ZOI larger than the ROI.
    refused(
        &[
            "correlate",
            path(&reference),
            path(&reference),
            "--zoi",
            "64",
            "--roi",
            "0,0,48,48",
            "--out",
            path(&out),
        ],
        "larger than the ROI",
    );
    // A flat image: every node low_contrast in the CSV, numbers finite, a warning naming the
    // image, and a failure: nothing was measured.
    let flat = dir.0.join("flat.png");
    write_png(&flat, &vec![1000u16; W * H], W, H);
    let output = dicstream(&[
        "correlate",
        path(&reference),
        path(&flat),
        "--out",
        path(&out),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{}: only 0 of", path(&flat))) && stderr.contains("low_contrast"),
        "{stderr}"
    );
    assert!(stderr.contains("nothing was measured"), "{stderr}");
    let csv = std::fs::read_to_string(out.join("field_0001.csv")).unwrap();
    for line in csv.lines().skip(1) {
        let row: Vec<&str> = line.split(',').collect();
        assert_eq!(row[9], "low_contrast", "{line}");
        assert!(
            row[..9]
                .iter()
                .all(|v| v.parse::<f64>().unwrap().is_finite()),
            "{line}"
        );
    }
}

/// An image of other material: no node may be called ok (the correlation finds a best match
/// everywhere; the final check refuses it), the run says so and fails. Next to a good image,
/// the bad one is named and the run succeeds.
#[test]
fn unrelated_images_are_refused_and_named() {
    let dir = TempDir::new("unrelated");
    let reference = dir.0.join("reference.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let unrelated = dir.0.join("unrelated.png");
    write_png(&unrelated, &unrelated_speckle(W, H, 5), W, H);
    let good = dir.0.join("good.png");
    write_png(&good, &render(W, H, &translation(0.4, 0.2).0, 2), W, H);
    let out = dir.0.join("out");
    let output = dicstream(&[
        "correlate",
        path(&reference),
        path(&unrelated),
        "--out",
        path(&out),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(stderr.contains("nothing was measured"), "{stderr}");
    let csv = std::fs::read_to_string(out.join("field_0001.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert!(!rows.is_empty());
    assert!(rows.iter().all(|row| row[9] != "ok"), "{csv}");
    let output = dicstream(&[
        "correlate",
        path(&reference),
        path(&good),
        path(&unrelated),
        "--out",
        path(&out),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("{}: only 0 of", path(&unrelated))),
        "{stderr}"
    );
    assert!(!stderr.contains(path(&good)), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let frames = summary["frames"].as_array().unwrap();
    assert_eq!(frames[0]["statuses"]["ok"], frames[0]["nodes"]);
    assert_eq!(frames[1]["statuses"]["ok"], 0);
}

/// A region of the reference, deformed wildly outside a polygon (beyond a triangle's long side,
/// another speckle altogether): the nodes whose ZOI leaves the triangle are `outside_region`
/// (not failed, not counted in the warning), every node inside is `ok`, the summary line and
/// `summary.json` say how many were measured; a mask of the same shape measures the same nodes.
#[test]
fn a_polygon_measures_its_nodes_and_marks_the_others_outside() {
    let dir = TempDir::new("polygon");
    let reference = dir.0.join("ref.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let moved = render(W, H, &translation(0.4, -0.3).0, 2);
    let other = unrelated_speckle(W, H, 3);
    // The triangle 8,8 180,8 8,150: (x − 8) / 172 + (y − 8) / 142 < 1 within its two straight
    // sides. The material moved up to a few pixels beyond the long side; past it, other material.
    let side = |x: f64, y: f64| (x - 8.0) / 172.0 + (y - 8.0) / 142.0;
    let deformed: Vec<u16> = (0..W * H)
        .map(|k| {
            let (x, y) = ((k % W) as f64, (k / W) as f64);
            if side(x, y) < 1.08 {
                moved[k]
            } else {
                other[k]
            }
        })
        .collect();
    let def = dir.0.join("def.png");
    write_png(&def, &deformed, W, H);
    let polygon = "8,8 180,8 8,150";
    let run = |region: &[&str], out: &Path| {
        let mut args = vec!["correlate", path(&reference), path(&def)];
        args.extend_from_slice(&["--zoi", "16", "--step", "8", "--out", path(out)]);
        args.extend_from_slice(region);
        let output = dicstream(&args);
        let stderr = String::from_utf8_lossy(&output.stderr).to_string();
        assert!(output.status.success(), "{stderr}");
        let csv = std::fs::read_to_string(out.join("field_0001.csv")).unwrap();
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        (stderr, csv, summary)
    };
    let (stderr, csv, summary) = run(&["--polygon", polygon], &dir.0.join("out"));
    assert!(!stderr.contains("warning"), "{stderr}");
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let (mut inside, mut outside) = (0, 0);
    for row in &rows {
        let (x, y): (f64, f64) = (row[0].parse().unwrap(), row[1].parse().unwrap());
        // The ZOI's far corner pixel (its centre + 7.5 px) decides: the other sides are the
        // mesh's own bounds.
        let far = side(x + 7.5, y + 7.5);
        match row[9] {
            "ok" => {
                inside += 1;
                assert!(far < 1.0, "{row:?}");
            }
            "outside_region" => {
                outside += 1;
                assert!(far > 0.99, "{row:?}");
            }
            status => panic!("{status}: {row:?}"),
        }
    }
    assert!(inside >= 50 && outside >= 50, "{inside} {outside}");
    assert!(
        stderr.contains(&format!(
            "(polygon 3 vertices), {inside} nodes, {inside} valid"
        )),
        "{stderr}"
    );
    assert_eq!(summary["settings"]["nodes_in_region"], inside);
    assert_eq!(summary["settings"]["region"]["polygons"][0], polygon);
    let frame = &summary["frames"][0];
    assert_eq!(frame["valid"], inside);
    assert_eq!(frame["nodes_in_region"], inside);
    assert_eq!(frame["statuses"]["outside_region"], outside);
    // The same region as a mask image: the same nodes, the same field.
    let mask: Vec<u16> = (0..W * H)
        .map(|k| {
            let (x, y) = ((k % W) as f64, (k / W) as f64);
            u16::from(x >= 8.0 && y >= 8.0 && side(x, y) < 1.0)
        })
        .collect();
    let mask_file = dir.0.join("mask.png");
    write_png(&mask_file, &mask, W, H);
    let (_, mask_csv, _) = run(&["--mask", path(&mask_file)], &dir.0.join("out_mask"));
    assert_eq!(mask_csv, csv);
    // Without the region, the nodes on the other material fail (and are no outside_region).
    let (_, _, all) = run(&[], &dir.0.join("out_all"));
    let frame = &all["frames"][0];
    assert_eq!(frame["statuses"]["outside_region"], 0);
    assert!(frame["valid"].as_u64() < frame["nodes"].as_u64(), "{frame}");
}

/// Every bad region is refused before anything is written, naming its setting.
#[test]
fn bad_regions_are_refused_naming_the_setting() {
    let dir = TempDir::new("bad_region");
    let reference = dir.0.join("ref.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let small_mask = dir.0.join("small_mask.png");
    write_png(&small_mask, &vec![1u16; 100 * 100], 100, 100);
    let black_mask = dir.0.join("black_mask.png");
    write_png(&black_mask, &vec![0u16; W * H], W, H);
    let garbage = dir.0.join("garbage.png");
    std::fs::write(&garbage, b"not an image").unwrap();
    let out = dir.0.join("out");
    let cases: [(&[&str], &str); 7] = [
        (&["--polygon", "10,10 100,10"], "has 2 vertices"),
        (
            &["--polygon", "10,10 100,100 100,10 10,100"],
            "crosses itself",
        ),
        (
            &["--polygon", "10,10 300,10 10,100"],
            "outside the 192x160 px image",
        ),
        (
            &["--polygon", "10,10 30,10 30,30 10,30"],
            "smaller than one 32 px ZOI",
        ),
        (
            &["--mask", path(&small_mask)],
            "is 100x100 px, expected 192x160 px",
        ),
        (&["--mask", path(&garbage)], "cannot be read"),
        (&["--mask", path(&black_mask)], "is empty"),
    ];
    for (region, needle) in cases {
        let mut args = vec!["correlate", path(&reference), path(&reference)];
        args.extend_from_slice(region);
        args.extend_from_slice(&["--out", path(&out)]);
        let output = dicstream(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
        assert!(
            stderr.contains(region[0]),
            "{:?} not named in {stderr}",
            region[0]
        );
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// `--gauge` and `--control-gauge` (issue 28 d2): a strain gauge reads the stretch, an
/// extensometer its elongation, the control gauge is the summary's `gauge`, a gauge where no
/// node is says why, and bad gauges are refused naming the option.
#[test]
fn gauges_read_the_stretch_where_they_are_placed() {
    let dir = TempDir::new("gauges");
    let (lx, ly) = (1.02, 0.99);
    let reference = dir.0.join("ref.png");
    let deformed = dir.0.join("def.png");
    write_png(&reference, &render(W, H, &translation(0.0, 0.0).0, 1), W, H);
    let stretched = common::camera::affine([[lx, 0.0], [0.0, ly]], [0.0, 0.0], [96.0, 80.0]).0;
    write_png(&deformed, &render(W, H, &stretched, 2), W, H);
    let out = dir.0.join("out");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "correlate",
            path(&reference),
            path(&deformed),
            "--zoi",
            "32",
            "--step",
            "8",
            "--out",
            path(&out),
        ];
        args.extend_from_slice(extra);
        dicstream(&args)
    };
    let output = run(&[
        "--gauge",
        "mid=rect:64,48,64,64",
        "--gauge",
        "arm=extensometer:40,80 150,80",
        "--gauge",
        "corner=rect:0,0,10,10",
        "--control-gauge",
        "mid",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("gauge mid (strain, "), "{stderr}");
    assert!(
        stderr.contains("gauge arm (extensometer): elongation"),
        "{stderr}"
    );
    assert!(
        stderr.contains("gauge corner (strain): no reading: 0 valid nodes inside the gauge"),
        "{stderr}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let frame = &summary["frames"][0];
    let gauges = frame["gauges"].as_array().unwrap();
    let mid = &gauges[0];
    assert_eq!(mid["name"], "mid");
    let exx = mid["strain"]["log"]["exx"].as_f64().unwrap();
    let eyy = mid["strain"]["log"]["eyy"].as_f64().unwrap();
    eprintln!(
        "mid: log exx {exx:.6} eyy {eyy:.6} over {} nodes",
        mid["nodes"]
    );
    assert!((exx - lx.ln()).abs() < 1e-3 && (eyy - ly.ln()).abs() < 1e-3);
    // The control gauge is the summary's gauge.
    assert_eq!(frame["gauge"], mid["strain"]);
    let arm = &gauges[1];
    let elongation = arm["elongation_px"].as_f64().unwrap();
    eprintln!(
        "arm: elongation {elongation:.4} px (truth {:.4})",
        (lx - 1.0) * 110.0
    );
    assert!((elongation - (lx - 1.0) * 110.0).abs() < 0.05);
    assert!((arm["nominal_strain"].as_f64().unwrap() - (lx - 1.0)).abs() < 5e-4);
    assert_eq!(gauges[2]["nodes"], 0);
    assert!(gauges[2]["no_reading"]
        .as_str()
        .unwrap()
        .contains("0 valid nodes"));
    // The default control gauge, the mesh's central half, reads the same homogeneous stretch.
    let output = run(&[]);
    assert!(output.status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let centre = summary["frames"][0]["gauge"]["log"]["exx"]
        .as_f64()
        .unwrap();
    assert!((centre - lx.ln()).abs() < 1e-3, "{centre}");
    for (args, expected) in [
        (
            ["--gauge", "arm=extensometer:40,80 500,80"],
            "point 500,80 is outside the 192x160 px image",
        ),
        (["--gauge", "arm=extensometer:40,80"], "two points"),
        (
            ["--control-gauge", "nosuch"],
            "control gauge nosuch is not one of the gauges",
        ),
    ] {
        let output = run(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{args:?}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
}
