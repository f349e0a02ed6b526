//! Tutorial 9: the character in a web browser (Volino, Huang & Hilton
//! 2015): a database exported as a self-contained static site (compact 4D
//! geometry, the Surface Motion Graph, a WebGL2 page); open its
//! `index.html` served (`surfmotion web serve --site SITE`) or from disk.
//!
//! cargo run --release --example 09_web_export -- synth_db synth_site

use surfmotion::web::{ExportOptions, export_db};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, site] = &a[..] else {
        return Err("usage: 09_web_export DB_DIR SITE_DIR".into());
    };
    let r = export_db(db.as_ref(), site.as_ref(), &ExportOptions::default())?;
    println!("{} bytes in {}", r.geometry.bytes, r.site.display());
    Ok(())
}
