//! Sections of `BENCHMARKS.md` that stand alone: each measures its own thing and renders its own
//! `## Title` section. A full run appends every one after the main tables; `--only NAME[,NAME]`
//! runs only the named ones and replaces just their sections in the existing `BENCHMARKS.md`
//! (everything else kept byte for byte), so one section can be regenerated without the rest.
//!
//! To add a section: a module with a `fn(&Tools) -> Option<String>` returning markdown that
//! starts with `## {title}\n` (None: skipped, and the reason printed), and one line in
//! [`SECTIONS`].

use std::path::{Path, PathBuf};

/// What a section may use: the release `asnr` binary, a Python with numpy (and the package),
/// the workspace root, and whether this is a smoke run.
#[allow(dead_code, reason = "each section reads what it needs; while SECTIONS is short some go unread")]
pub(crate) struct Tools {
    pub(crate) asnr: Option<PathBuf>,
    pub(crate) python: Option<PathBuf>,
    pub(crate) asnr_python: Option<PathBuf>,
    pub(crate) root: PathBuf,
    pub(crate) quick: bool,
}

/// One stand-alone section: the name `--only` takes, its heading, and what renders it.
pub(crate) struct Section {
    pub(crate) name: &'static str,
    pub(crate) title: &'static str,
    pub(crate) run: fn(&Tools) -> Option<String>,
}

/// Every stand-alone section, in the order a full run appends them.
pub(crate) const SECTIONS: &[Section] = &[
    Section { name: "phase-maps", title: "2-D phase maps against the radial engine", run: crate::phase_maps::section },
    Section {
        name: "fft-azimuth",
        title: "The FFT path's sampling judged over azimuth",
        run: crate::fft_azimuth::section,
    },
    Section { name: "sfr", title: crate::sfr::TITLE, run: crate::sfr::section },
    Section {
        name: "exact",
        title: "The flat lens's exact image: the cost of `pupil_mapping = \"exact\"`",
        run: crate::exact_map::section,
    },
    Section {
        name: "gradients",
        title: "Gradients: the value and its gradient side by side",
        run: crate::gradients::section,
    },
    Section { name: "gradients-design", title: crate::gradients_design::TITLE, run: crate::gradients_design::section },
    Section {
        name: "gradients-families",
        title: crate::gradients_families::TITLE,
        run: crate::gradients_families::section,
    },
    Section {
        name: "gradients-bias",
        title: "Gradients: a library's parameter bias",
        run: crate::gradients_bias::section,
    },
    Section { name: "table-rule", title: crate::table_rule::TITLE, run: crate::table_rule::section },
    Section { name: "psf-stack", title: crate::psf_stack::TITLE, run: crate::psf_stack::section },
    Section { name: "freeform", title: crate::freeform::TITLE, run: crate::freeform::section },
    Section { name: "gds_scale", title: "GDS layout at scale", run: crate::gds_scale::run },
    Section { name: "map", title: crate::map_numpy::TITLE, run: crate::map_numpy::section },
    Section { name: "closed", title: crate::closed_ladder::TITLE, run: crate::closed_ladder::section },
    Section { name: "otf-paths", title: crate::otf_paths::TITLE, run: crate::otf_paths::section },
];

/// The sections `--only` names, or an error listing the known names.
pub(crate) fn select(names: &str) -> Result<Vec<&'static Section>, String> {
    names
        .split(',')
        .map(|name| {
            SECTIONS.iter().find(|s| s.name == name.trim()).ok_or_else(|| {
                let known: Vec<&str> = SECTIONS.iter().map(|s| s.name).collect();
                format!("unknown section `{name}` for --only (known: {})", known.join(", "))
            })
        })
        .collect()
}

/// Run `sections` and put each into `markdown` (see [`splice`]); a section that returns None is
/// left as it was.
pub(crate) fn render_into(markdown: &mut String, sections: &[&Section], tools: &Tools) {
    for section in sections {
        eprintln!("section `{}`: {}", section.name, section.title);
        match (section.run)(tools) {
            Some(text) => *markdown = splice(markdown, section.title, &text),
            None => eprintln!("section `{}` skipped", section.name),
        }
    }
}

/// `document` with its section headed `## {title}` (up to the next `## ` heading or the end)
/// replaced by `text`, or `text` appended when there is no such section.
pub(crate) fn splice(document: &str, title: &str, text: &str) -> String {
    let heading = format!("## {title}\n");
    assert!(text.starts_with(&heading), "a section's text starts with its heading `## {title}`");
    let text = if text.ends_with('\n') { text.to_string() } else { format!("{text}\n") };
    let start =
        if document.starts_with(&heading) { Some(0) } else { document.find(&format!("\n{heading}")).map(|i| i + 1) };
    match start {
        Some(start) => {
            let after = start + heading.len();
            let end = document[after..].find("\n## ").map_or(document.len(), |i| after + i + 1);
            let separator = if end < document.len() { "\n" } else { "" };
            format!("{}{}{}{}", &document[..start], text, separator, &document[end..])
        }
        None => {
            let glue = if document.is_empty() || document.ends_with("\n\n") {
                ""
            } else if document.ends_with('\n') {
                "\n"
            } else {
                "\n\n"
            };
            format!("{document}{glue}{text}")
        }
    }
}

/// The path of `BENCHMARKS.md` under `root`.
pub(crate) fn benchmarks(root: &Path) -> PathBuf {
    root.join("BENCHMARKS.md")
}

#[cfg(test)]
mod tests {
    use super::splice;

    #[test]
    fn splice_replaces_only_its_section() {
        let doc = "# B\n\n## A\nold a\n\n## X\nold x\n\n## C\nc\n";
        let new = splice(doc, "X", "## X\nnew x\n");
        assert_eq!(new, "# B\n\n## A\nold a\n\n## X\nnew x\n\n## C\nc\n");
        let last = splice(doc, "C", "## C\nnew c\n");
        assert_eq!(last, "# B\n\n## A\nold a\n\n## X\nold x\n\n## C\nnew c\n");
        let added = splice(doc, "D", "## D\nd\n");
        assert_eq!(added, "# B\n\n## A\nold a\n\n## X\nold x\n\n## C\nc\n\n## D\nd\n");
    }
}
