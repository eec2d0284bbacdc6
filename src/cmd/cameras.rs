//! `dicstream cameras [--json]`: the GenICam cameras Aravis finds (GigE Vision discovery on
//! every network interface, USB3 Vision): id, vendor, model, serial, address, sensor size,
//! pixel formats. Needs the `genicam` feature; without it, a clear error (exit 1).

/// Options of `dicstream cameras`.
#[derive(Debug, clap::Args)]
pub struct CamerasArgs {
    /// Print a JSON array on stdout (and nothing else there)
    #[arg(long)]
    pub json: bool,
}

/// The message of a build without the `genicam` feature.
#[cfg_attr(feature = "genicam", allow(dead_code))]
pub const NO_GENICAM: &str = "this dicstream was built without the `genicam` feature, so it \
    cannot reach GenICam cameras: install Aravis (Debian/Ubuntu: apt-get install libaravis-dev \
    libusb-1.0-0-dev) and build with `cargo build --release --features genicam`";

#[cfg(not(feature = "genicam"))]
pub fn run(_args: CamerasArgs) -> anyhow::Result<()> {
    anyhow::bail!(NO_GENICAM)
}

#[cfg(feature = "genicam")]
pub fn run(args: CamerasArgs) -> anyhow::Result<()> {
    use crate::genicam::device::list_cameras;
    use producer::genicam::PixelFormat;

    let cameras = list_cameras();
    if args.json {
        let list: Vec<serde_json::Value> = cameras
            .iter()
            .map(|c| {
                serde_json::json!({
                    "id": c.id,
                    "vendor": c.vendor,
                    "model": c.model,
                    "serial": c.serial,
                    "address": c.address,
                    "protocol": c.protocol,
                    "sensor_width_px": c.sensor_width_px,
                    "sensor_height_px": c.sensor_height_px,
                    "pixel_formats": c.pixel_formats,
                    "open_error": c.open_error,
                })
            })
            .collect();
        println!("{}", serde_json::to_string_pretty(&list)?);
        return Ok(());
    }
    if cameras.is_empty() {
        println!(
            "no GenICam camera found (GigE Vision: same subnet, firewall open to UDP 3956; USB3 \
             Vision: udev rules giving access to the device)"
        );
        return Ok(());
    }
    for c in &cameras {
        println!("{}", c.id);
        println!("  vendor:  {}", c.vendor);
        println!("  model:   {}", c.model);
        println!("  serial:  {}", c.serial);
        println!("  address: {} ({})", c.address, c.protocol);
        match &c.open_error {
            Some(e) => println!("  could not be opened to read its sensor and formats: {e}"),
            None => {
                println!("  sensor:  {}x{} px", c.sensor_width_px, c.sensor_height_px);
                let usable: Vec<&str> = c
                    .pixel_formats
                    .iter()
                    .filter(|f| f.parse::<PixelFormat>().is_ok())
                    .map(String::as_str)
                    .collect();
                println!(
                    "  pixel formats: {} (dicstream publishes: {})",
                    c.pixel_formats.join(", "),
                    if usable.is_empty() {
                        "none".to_string()
                    } else {
                        usable.join(", ")
                    }
                );
            }
        }
    }
    println!(
        "use one with: dicstream producer --camera genicam:{}",
        cameras[0].id
    );
    Ok(())
}
