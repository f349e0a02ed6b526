//! Writer options that apply to one output format only: [`GlbOptions`]'
//! quantisation and normals off for a `.glb`, [`UsdOptions`]' normals off
//! for a `.usda`. Given for another output they are refused before any
//! work, not dropped without a word (issue 46, item 11). The refusal names
//! the options as their callers set them; the CLI prints its flags.

use crate::mesh::io::MeshFormat;
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::usd::UsdOptions;
use std::fmt;
use std::path::Path;

/// Options of one output format given for an output of another.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct FormatOnlyOptions {
    /// The options given, in the callers' words
    /// (`` `GlbOptions::quantize` ``, `` `GlbOptions::normals` false ``).
    pub options: Vec<&'static str>,
    /// The format they apply to: `glb` or `usda`.
    pub format: &'static str,
    /// The output they were given for (its path, or the caller's words
    /// for a folder's format).
    pub output: String,
}

impl fmt::Display for FormatOnlyOptions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let many = self.options.len() > 1;
        write!(
            f,
            "{} {} to .{format} output only, not {}: leave {} out or write a .{format}",
            self.options.join(" and "),
            if many { "apply" } else { "applies" },
            self.output,
            if many { "them" } else { "it" },
            format = self.format,
        )
    }
}

/// Refuses `glb`'s quantisation or normals off unless the output is a GLB
/// (`is_glb`); `output` names it.
pub fn refuse_unless_glb(
    glb: &GlbOptions,
    is_glb: bool,
    output: &str,
) -> Result<(), FormatOnlyOptions> {
    let given: Vec<&'static str> = [
        (glb.quantize, "`GlbOptions::quantize`"),
        (!glb.normals, "`GlbOptions::normals` false"),
    ]
    .into_iter()
    .filter_map(|(on, option)| on.then_some(option))
    .collect();
    refuse(given, "glb", is_glb, output)
}

/// Refuses `usd`'s normals off unless the output is a `.usda` (`is_usda`);
/// `output` names it.
pub fn refuse_unless_usda(
    usd: &UsdOptions,
    is_usda: bool,
    output: &str,
) -> Result<(), FormatOnlyOptions> {
    let given = if usd.normals {
        vec![]
    } else {
        vec!["`UsdOptions::normals` false"]
    };
    refuse(given, "usda", is_usda, output)
}

/// Both refusals for the mesh output `path` (its format by its name),
/// the GLB's first.
pub fn refuse_other_formats(
    glb: &GlbOptions,
    usd: &UsdOptions,
    path: &Path,
) -> Result<(), FormatOnlyOptions> {
    let name = path.display().to_string();
    let format = MeshFormat::of(path);
    refuse_unless_glb(glb, format == Some(MeshFormat::Glb), &name)?;
    refuse_unless_usda(usd, format == Some(MeshFormat::Usda), &name)
}

fn refuse(
    options: Vec<&'static str>,
    format: &'static str,
    applies: bool,
    output: &str,
) -> Result<(), FormatOnlyOptions> {
    if applies || options.is_empty() {
        return Ok(());
    }
    Err(FormatOnlyOptions {
        options,
        format,
        output: output.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Quantisation and normals off for a point cache: both named, in one
    /// sentence; for a GLB, none; normals off for a GLB: the USD's refused.
    #[test]
    fn format_only_options_are_refused_for_other_outputs() {
        let glb = GlbOptions {
            quantize: true,
            normals: false,
        };
        let e = refuse_other_formats(&glb, &UsdOptions::DEFAULT, Path::new("o.pc2")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "`GlbOptions::quantize` and `GlbOptions::normals` false apply to .glb output only, not o.pc2: leave them out or write a .glb"
        );
        assert!(refuse_other_formats(&glb, &UsdOptions::DEFAULT, Path::new("o.GLB")).is_ok());
        let usd = UsdOptions { normals: false };
        let e = refuse_other_formats(&GlbOptions::default(), &usd, Path::new("o.glb")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "`UsdOptions::normals` false applies to .usda output only, not o.glb: leave it out or write a .usda"
        );
        assert!(refuse_unless_usda(&usd, true, "o.usda").is_ok());
        assert!(refuse_unless_glb(&GlbOptions::default(), false, "--format pc2").is_ok());
    }
}
