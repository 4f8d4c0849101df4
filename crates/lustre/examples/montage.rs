//! Tiles PNG images into one (the before/after frames, references and difference maps of
//! `scripts/setup_study.sh`): `montage OUT.png COLUMNS SCALE IN.png...`, row by row, each image
//! enlarged SCALE times (nearest), 4 px white gaps. Images of different sizes are placed at the
//! top left of cells as large as the largest.

use anyhow::{bail, Context};
use image::{Rgb, RgbImage};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        bail!("usage: montage OUT.png COLUMNS SCALE IN.png...");
    }
    let cols: u32 = args[1].parse().context("COLUMNS")?;
    let scale: u32 = args[2].parse().context("SCALE")?;
    if !(1..=64).contains(&cols) || !(1..=16).contains(&scale) {
        bail!("COLUMNS must be 1..=64 and SCALE 1..=16");
    }
    let images: Vec<RgbImage> = args[3..]
        .iter()
        .map(|p| Ok(image::open(p).with_context(|| p.clone())?.to_rgb8()))
        .collect::<anyhow::Result<_>>()?;
    let (cw, ch) = images
        .iter()
        .fold((0, 0), |(w, h), i| (w.max(i.width()), h.max(i.height())));
    let (cw, ch, gap) = (cw * scale, ch * scale, 4);
    let n = images.len() as u32;
    let rows = n.div_ceil(cols);
    let mut out = RgbImage::from_pixel(
        cols * cw + (cols - 1) * gap,
        rows * ch + (rows - 1) * gap,
        Rgb([255, 255, 255]),
    );
    for (k, img) in images.iter().enumerate() {
        let (c, r) = (k as u32 % cols, k as u32 / cols);
        let (x0, y0) = (c * (cw + gap), r * (ch + gap));
        for y in 0..img.height() * scale {
            for x in 0..img.width() * scale {
                out.put_pixel(x0 + x, y0 + y, *img.get_pixel(x / scale, y / scale));
            }
        }
    }
    out.save(&args[0]).with_context(|| args[0].clone())?;
    Ok(())
}
