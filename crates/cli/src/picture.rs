//! Writing pictures: SVG always, PNG where asked (rendered from the SVG with
//! resvg, text in the system's sans-serif font).

use crate::exit::BadInput;
use anyhow::{Context, Result};
use pcaline_io::{OutputSet, write_atomic};
use resvg::{tiny_skia, usvg};
use std::path::Path;

/// Renders an SVG document to PNG bytes. Text needs a system font; without
/// one the picture is drawn without its labels, and a warning says so.
pub fn svg_to_png(svg: &str) -> Result<Vec<u8>> {
    let mut options = usvg::Options::default();
    let db = options.fontdb_mut();
    db.load_system_fonts();
    // The pictures ask for the generic "sans-serif", which usvg maps to
    // Arial: map it to the first sans family this machine has.
    let families: Vec<String> =
        db.faces().flat_map(|f| f.families.iter().map(|(name, _)| name.clone())).collect();
    let sans = ["DejaVu Sans", "Liberation Sans", "Noto Sans", "Arial", "Helvetica", "FreeSans"]
        .into_iter()
        .find(|want| families.iter().any(|f| f == want))
        .map(str::to_string)
        .or_else(|| families.first().cloned());
    match sans {
        Some(family) => {
            db.set_sans_serif_family(family.clone());
            options.font_family = family;
        }
        None => eprintln!("warning: no system font found: the PNG has no text (the SVG has it)"),
    }
    let tree = usvg::Tree::from_str(svg, &options).context("rendering the picture")?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .context("the picture is too large to render")?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    pixmap.encode_png().context("encoding the PNG")
}

/// The picture formats `-o` takes, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PictureFormat {
    /// `.svg`
    Svg,
    /// `.png`, rendered from the SVG.
    Png,
}

impl PictureFormat {
    /// The format `path` names by its extension (any case); an error that
    /// names the path and the supported extensions otherwise, before any
    /// work is done.
    pub fn of(path: &Path) -> Result<Self> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("svg") => Ok(PictureFormat::Svg),
            Some("png") => Ok(PictureFormat::Png),
            _ => Err(BadInput(format!(
                "{}: unsupported picture format (supported: .svg, .png)",
                path.display()
            ))
            .into()),
        }
    }
}

/// Writes `svg` to `path` (atomically), as SVG or PNG by the extension
/// ([`PictureFormat::of`]).
pub fn write_picture(path: &Path, svg: &str) -> Result<()> {
    match PictureFormat::of(path)? {
        PictureFormat::Png => write_atomic(path, &svg_to_png(svg)?)?,
        PictureFormat::Svg => write_atomic(path, svg.as_bytes())?,
    }
    Ok(())
}

/// Adds `name.svg` in `dir` to `outputs`, and `name.png` too when `png`.
pub fn add_svg_and_png(
    outputs: &mut OutputSet,
    dir: &Path,
    name: &str,
    svg: &str,
    png: bool,
) -> Result<()> {
    outputs.add(&dir.join(format!("{name}.svg")), svg.as_bytes())?;
    if png {
        outputs.add(&dir.join(format!("{name}.png")), &svg_to_png(svg)?)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_a_png() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="20" height="10"><rect width="20" height="10" fill="red"/></svg>"#;
        let png = svg_to_png(svg).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
    }

    #[test]
    fn picture_formats_by_extension() {
        assert_eq!(PictureFormat::of(Path::new("a/b.SVG")).unwrap(), PictureFormat::Svg);
        assert_eq!(PictureFormat::of(Path::new("b.png")).unwrap(), PictureFormat::Png);
        for bad in ["x.pdf", "x", "x.svg.gz"] {
            let e = PictureFormat::of(Path::new(bad)).unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains(".svg, .png"), "{e}");
        }
    }
}
