//! Where the text of the PNG figures comes from.
//!
//! plotters' `ab_glyph` backend renders no text until a TrueType/OpenType font is registered from
//! bytes. We embed no font (a full Unicode sans font with θ/φ/ω glyphs is several hundred KiB);
//! instead the first readable font among `$LUSTRE_PLOT_FONT` and a list of common system paths
//! (DejaVu Sans, Liberation Sans, Noto Sans, FreeSans, Arial/Helvetica on macOS and Windows) is
//! loaded once per process and registered as `sans-serif` (`LUSTRE_PLOT_FONT=none` skips it). When none is found, PNG figures are
//! drawn without text (the curves, discs, markers and the colour bar are still drawn), while the
//! SVG figures keep all their labels because SVG text is rendered by the viewer.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Environment variable naming a `.ttf`/`.otf` file to use for PNG text; the value `none`
/// disables PNG text (reproducible, font-independent images).
pub const FONT_ENV: &str = "LUSTRE_PLOT_FONT";

const CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/local/share/fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/liberation2/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/noto/NotoSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/gnu-free/FreeSans.ttf",
    "/Library/Fonts/Arial.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "/System/Library/Fonts/Helvetica.ttc",
    "C:\\Windows\\Fonts\\arial.ttf",
    "C:\\Windows\\Fonts\\segoeui.ttf",
];

static LOADED: OnceLock<Option<PathBuf>> = OnceLock::new();

/// Registers a font for PNG text on first use; returns the file it came from, or `None` when no
/// usable font was found (PNG figures are then drawn without text).
pub fn font_source() -> Option<&'static Path> {
    LOADED.get_or_init(load).as_deref()
}

/// True when PNG figures can carry text.
pub fn font_available() -> bool {
    font_source().is_some()
}

fn load() -> Option<PathBuf> {
    let env = std::env::var_os(FONT_ENV).map(PathBuf::from);
    if env.as_deref() == Some(Path::new("none")) {
        return None;
    }
    env.into_iter()
        .chain(CANDIDATES.iter().map(PathBuf::from))
        .find(|p| try_register(p))
}

fn try_register(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    // plotters keeps a `'static` reference to the font; this runs at most once per process.
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, bytes).is_ok()
}
