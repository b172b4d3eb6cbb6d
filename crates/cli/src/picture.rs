//! Writing pictures: SVG always, PNG where asked (rendered from the SVG with
//! resvg, text in the system's sans-serif font).

use anyhow::{Context, Result};
use pcaline_io::write_atomic;
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};

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

/// Writes `svg` to `path` (atomically): as PNG when the path ends in `.png`,
/// else as SVG.
pub fn write_picture(path: &Path, svg: &str) -> Result<()> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
        write_atomic(path, &svg_to_png(svg)?)?;
    } else {
        write_atomic(path, svg.as_bytes())?;
    }
    Ok(())
}

/// Writes `name.svg` in `dir`, and `name.png` too when `png`; returns the paths written.
pub fn write_svg_and_png(dir: &Path, name: &str, svg: &str, png: bool) -> Result<Vec<PathBuf>> {
    let svg_path = dir.join(format!("{name}.svg"));
    write_atomic(&svg_path, svg.as_bytes())?;
    let mut written = vec![svg_path];
    if png {
        let png_path = dir.join(format!("{name}.png"));
        write_atomic(&png_path, &svg_to_png(svg)?)?;
        written.push(png_path);
    }
    Ok(written)
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
}
