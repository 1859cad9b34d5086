//! `cargo xtask tidy`: architecture and house-style checks that read the source tree (run
//! by `cargo xtask ci`, and as a `#[test]` by `cargo test --workspace`).
//!
//! - **Layers** (DESIGN.md §2): every `crates/*/Cargo.toml`, `validation/`, `xtask/` and
//!   `benches/` manifest is read, and each dependency (normal, dev or build) on a demcon
//!   crate must point down the layer picture; siblings on a layer never know each other;
//!   `demcon-post` uses no physics crate; only `demcon-network` depends on `faer`; only
//!   `demcon-scene` depends on `ron`.
//! - **File headers**: every `.rs` file under `crates/`, `xtask/`, `benches/` and `validation/` opens with a
//!   `//!` line saying what it is for.
//! - **Cases import no case**: a module of `validation/src/cases/` that the registry runs as a
//!   case (`run: <module>::run` in `cases/mod.rs`) is named through `super::` by no other
//!   module there; what two cases share lives in a shared module.

use std::fmt;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// Layer of each package of the workspace (DESIGN.md §2). Dependencies point to a strictly
/// lower layer; packages on one layer are siblings and never depend on each other.
const LAYERS: &[(&str, u32)] = &[
    ("demcon-core", 0),
    // Layer 0 (siblings on core): packing | graph.
    ("demcon-packing", 1),
    ("demcon-graph", 1),
    ("demcon-network", 2),
    // Layer 2 (siblings): thermal | electric.
    ("demcon-thermal", 3),
    ("demcon-electric", 3),
    // Layer 3 (siblings): model | post | plot.
    ("demcon-model", 4),
    ("demcon-post", 4),
    ("demcon-plot", 4),
    ("demcon-scene", 5),
    // Layer 5 (siblings): the CLI | the validation cases.
    ("demcon", 6),
    ("validation", 6),
    // The Python package (python/): beside the CLI, on the scene crate.
    ("demcon-python", 6),
    // Tools: may use any crate; nothing uses them.
    ("xtask", 7),
    ("demcon-benches", 7),
];

/// The picture's layer names for the rank used in [`LAYERS`] (packing and graph sit on
/// core: "layer 0" of DESIGN.md is split here into core and its two siblings).
fn layer_name(rank: u32) -> &'static str {
    match rank {
        0 => "layer 0 (core)",
        1 => "layer 0 (packing | graph, on core)",
        2 => "layer 1 (network)",
        3 => "layer 2 (thermal | electric)",
        4 => "layer 3 (model | post | plot)",
        5 => "layer 4 (scene)",
        6 => "layer 5 (CLI | validation)",
        _ => "tools (xtask | benches)",
    }
}

/// Crates that `demcon-post` must not use: it takes plain slices, not solver results.
const POST_FORBIDDEN: &[&str] = &["demcon-thermal", "demcon-electric", "demcon-model"];

/// External crates only one package may use, and why.
const EXCLUSIVE: &[(&str, &str, &str)] = &[
    (
        "faer",
        "demcon-network",
        "faer is the slowest crate to compile; it stays in demcon-network",
    ),
    ("ron", "demcon-scene", "only demcon-scene knows RON"),
];

/// One broken rule: the crate, the dependency and the rule.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The package whose manifest has the dependency.
    pub krate: String,
    /// The dependency.
    pub dependency: String,
    /// The rule it breaks.
    pub rule: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} depends on {}: {}", self.krate, self.dependency, self.rule)
    }
}

/// A dependency as read from a manifest: its name and section (`dependencies`,
/// `dev-dependencies`, `build-dependencies`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Dependency {
    /// Package name (the key in the manifest).
    pub name: String,
    /// Section it was listed in.
    pub section: String,
}

/// The package name and the dependencies of a `Cargo.toml` (a small reader for the flat
/// manifests of this workspace: `[package] name`, `[*dependencies]` keys, and
/// `[*dependencies.NAME]` tables, including `[target.'…'.dependencies]`).
pub fn read_manifest(text: &str) -> (Option<String>, Vec<Dependency>) {
    let mut name = None;
    let mut deps = Vec::new();
    let mut section = String::new();
    for raw in text.lines() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        if let Some(header) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            let header = header.trim_matches(['[', ']']).trim();
            section = header.to_string();
            // `[dependencies.foo]` or `[target.'cfg(..)'.dev-dependencies.foo]`.
            for kind in ["dependencies", "dev-dependencies", "build-dependencies"] {
                if let Some(pos) = header.find(&format!("{kind}.")) {
                    let starts_word = pos == 0 || header[..pos].ends_with('.');
                    if starts_word {
                        deps.push(Dependency {
                            name: header[pos + kind.len() + 1..].trim_matches('"').to_string(),
                            section: kind.to_string(),
                        });
                        section = String::new();
                    }
                }
            }
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            continue;
        };
        let key = key.trim();
        if section == "package" && key == "name" {
            name = Some(value.trim().trim_matches('"').to_string());
        }
        let kind = section.rsplit('.').next().unwrap_or("");
        if matches!(kind, "dependencies" | "dev-dependencies" | "build-dependencies") {
            // `foo.workspace = true` or `foo = …`.
            let dep = key.split('.').next().unwrap_or(key).trim_matches('"');
            deps.push(Dependency {
                name: dep.to_string(),
                section: kind.to_string(),
            });
        }
    }
    (name, deps)
}

/// The layer rules applied to one package's dependencies.
pub fn check_dependencies(krate: &str, deps: &[Dependency]) -> Vec<Violation> {
    let rank = |n: &str| LAYERS.iter().find(|(c, _)| *c == n).map(|(_, r)| *r);
    let mut out = Vec::new();
    let broke = |dep: &Dependency, rule: String| Violation {
        krate: krate.to_string(),
        dependency: format!("{} ({})", dep.name, dep.section),
        rule,
    };
    let own = rank(krate);
    if own.is_none() && krate.starts_with("demcon") {
        out.push(Violation {
            krate: krate.to_string(),
            dependency: "-".into(),
            rule: "a workspace crate missing from the layer table of xtask/src/tidy.rs (LAYERS): give it its layer from DESIGN.md §2".into(),
        });
    }
    for dep in deps {
        if let Some((_, only, why)) = EXCLUSIVE.iter().find(|(d, _, _)| *d == dep.name) {
            if krate != *only {
                out.push(broke(
                    dep,
                    format!("only {only} may depend on {} ({why})", dep.name),
                ));
            }
            continue;
        }
        let ours = dep.name.starts_with("demcon") || dep.name == "validation" || dep.name == "xtask";
        if !ours {
            continue;
        }
        let (Some(r_c), Some(r_d)) = (own, rank(&dep.name)) else {
            if rank(&dep.name).is_none() {
                out.push(broke(
                    dep,
                    "a workspace crate missing from the layer table of xtask/src/tidy.rs (LAYERS)".into(),
                ));
            }
            continue;
        };
        if r_d == r_c {
            out.push(broke(
                dep,
                format!(
                    "siblings on {} never depend on each other; move what they share down a layer",
                    layer_name(r_c)
                ),
            ));
        } else if r_d > r_c {
            out.push(broke(
                dep,
                format!(
                    "dependencies point down only ({} is on {}, above {})",
                    dep.name,
                    layer_name(r_d),
                    layer_name(r_c)
                ),
            ));
        } else if krate == "demcon-post" && POST_FORBIDDEN.contains(&dep.name.as_str()) {
            out.push(broke(
                dep,
                "demcon-post takes plain slices and uses no physics crate (thermal, electric, model)".into(),
            ));
        }
    }
    out
}

/// The manifests whose dependencies are checked: `crates/*`, `validation`, `xtask`,
/// `benches`.
fn manifests(root: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let crates = root.join("crates");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&crates)
        .with_context(|| format!("reading {}", crates.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    dirs.sort();
    for d in dirs
        .into_iter()
        .chain(["validation", "xtask", "benches"].map(|d| root.join(d)))
    {
        let m = d.join("Cargo.toml");
        if m.is_file() {
            out.push(m);
        }
    }
    Ok(out)
}

/// Every layer violation of the workspace at `root`.
pub fn layer_violations(root: &Path) -> Result<Vec<Violation>> {
    let mut out = Vec::new();
    for m in manifests(root)? {
        let text = std::fs::read_to_string(&m).with_context(|| format!("reading {}", m.display()))?;
        let (name, deps) = read_manifest(&text);
        let name = name.with_context(|| format!("{}: no [package] name", m.display()))?;
        out.extend(check_dependencies(&name, &deps));
    }
    Ok(out)
}

/// `.rs` files under `dir` whose first line is not a `//!` doc comment.
fn files_without_header(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut files = Vec::new();
    rust_files(dir, &mut files)?;
    for p in files {
        let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        if !text.lines().next().is_some_and(|l| l.starts_with("//!")) {
            out.push(p);
        }
    }
    Ok(())
}

/// The modules the registry of `cases/mod.rs` (its text) runs as cases: `run: <module>::run`.
pub fn case_modules(registry: &str) -> Vec<String> {
    let mut out: Vec<String> = registry
        .split("run:")
        .skip(1)
        .filter_map(|rest| rest.trim_start().split("::run").next())
        .map(|m| m.trim().to_string())
        .filter(|m| !m.is_empty() && m.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// The case modules (of `cases`) that the module `own`'s source `text` names through
/// `super::` (other than itself).
pub fn imported_cases<'c>(own: &str, text: &str, cases: &'c [String]) -> Vec<&'c str> {
    cases
        .iter()
        .filter(|c| c.as_str() != own)
        .filter(|c| {
            text.match_indices(&format!("super::{c}")).any(|(i, m)| {
                !text[i + m.len()..]
                    .chars()
                    .next()
                    .is_some_and(|ch| ch.is_ascii_alphanumeric() || ch == '_')
            })
        })
        .map(String::as_str)
        .collect()
}

/// "cases import no case": every `validation/src/cases/*.rs` against the registry's cases.
fn case_imports(root: &Path) -> Result<Vec<String>> {
    let dir = root.join("validation/src/cases");
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let registry =
        std::fs::read_to_string(dir.join("mod.rs")).context("reading validation/src/cases/mod.rs")?;
    let cases = case_modules(&registry);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    for p in files {
        let own = p
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default()
            .to_string();
        let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        for c in imported_cases(&own, &text, &cases) {
            out.push(format!(
                "validation/src/cases/{own}.rs names the case `{c}`: cases import no case (move what they share \
                 into a shared module)"
            ));
        }
    }
    Ok(out)
}

/// A rule on the library sources: `pattern` may appear (outside `#[cfg(test)]` code) only in the
/// files of `allowed` (paths from the workspace root); `why` says what the rule keeps.
pub struct TextRule {
    /// The text that marks the thing the rule confines.
    pub pattern: &'static str,
    /// The files where it may appear.
    pub allowed: &'static [&'static str],
    /// What the rule keeps, for the message.
    pub why: &'static str,
}

/// The text rules `cargo xtask tidy` checks on `crates/*/src`.
pub const TEXT_RULES: &[TextRule] = &[
    TextRule {
        pattern: "let beta",
        allowed: &["crates/demcon-network/src/pcg.rs"],
        why: "one conjugate-gradient recurrence: implement `pcg::Krylov` and call `pcg::cg`",
    },
    TextRule {
        pattern: "convert::problem(",
        allowed: &["crates/demcon-scene/src/validate.rs"],
        why: "a scene is converted once, by `Scene::from_config`: read `Scene::problem`",
    },
    TextRule {
        pattern: "convert::model_params(",
        allowed: &["crates/demcon-scene/src/validate.rs"],
        why: "a scene is converted once, by `Scene::from_config`: read `Scene::problem().model`",
    },
    TextRule {
        pattern: "[..n]",
        allowed: &["crates/demcon-graph/src/wall.rs"],
        why: "the wall nodes follow the particles in node vectors: split them with `WallContacts::particle_part` \
              or `WallContacts::split_nodes`",
    },
    TextRule {
        pattern: "Schedule::new(",
        allowed: &["crates/demcon-thermal/src/march.rs"],
        why: "one time march: implement `march::Stepper` and call `march::march`",
    },
];

/// The part of a source file before its `#[cfg(test)]` module.
fn library_part(text: &str) -> &str {
    text.find("\n#[cfg(test)]").map_or(text, |i| &text[..i])
}

/// `.rs` files under `dir`, recursively (`target` folders skipped), sorted.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n == "target") {
                continue;
            }
            rust_files(&p, out)?;
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
    Ok(())
}

/// Violations of [`TEXT_RULES`] in the library sources (`crates/*/src`) of `root`.
fn text_rule_violations(root: &Path) -> Result<Vec<String>> {
    let mut files = Vec::new();
    let crates = root.join("crates");
    if crates.is_dir() {
        for krate in std::fs::read_dir(&crates)?.filter_map(|e| e.ok().map(|e| e.path())) {
            let src = krate.join("src");
            if src.is_dir() {
                rust_files(&src, &mut files)?;
            }
        }
    }
    files.sort();
    let mut out = Vec::new();
    for p in files {
        let rel = p
            .strip_prefix(root)
            .unwrap_or(&p)
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
        let lib = library_part(&text);
        for rule in TEXT_RULES {
            if lib.contains(rule.pattern) && !rule.allowed.contains(&rel.as_str()) {
                out.push(format!("{rel} contains `{}`: {}", rule.pattern, rule.why));
            }
        }
    }
    Ok(out)
}

/// Runs every check on the workspace at `root`; the error lists every violation.
pub fn check(root: &Path) -> Result<()> {
    let mut problems: Vec<String> = layer_violations(root)?.iter().map(|v| v.to_string()).collect();
    let mut bare = Vec::new();
    for d in ["crates", "xtask", "benches", "validation"] {
        let dir = root.join(d);
        if dir.is_dir() {
            files_without_header(&dir, &mut bare)?;
        }
    }
    problems.extend(bare.iter().map(|p| {
        format!(
            "{}: the file must open with a `//!` line saying what it is for",
            p.strip_prefix(root).unwrap_or(p).display()
        )
    }));
    problems.extend(case_imports(root)?);
    problems.extend(text_rule_violations(root)?);
    if problems.is_empty() {
        Ok(())
    } else {
        bail!(
            "tidy found {} problem(s):\n  {}",
            problems.len(),
            problems.join("\n  ")
        )
    }
}

/// The workspace root (this crate's parent folder).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// `cargo xtask tidy`.
pub fn run() -> Result<()> {
    check(&workspace_root())?;
    eprintln!("tidy: layers, exclusive dependencies, file headers, case imports and text rules are in order");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deps(names: &[&str]) -> Vec<Dependency> {
        names
            .iter()
            .map(|n| Dependency {
                name: n.to_string(),
                section: "dependencies".into(),
            })
            .collect()
    }

    /// The workspace as it is obeys the layer picture and the header rule.
    #[test]
    fn a_case_named_by_another_module_is_found() {
        let registry = "Case { id: \"a\", run: alpha::run },\n Case { id: \"b\", run: beta_2::run }";
        let cases = case_modules(registry);
        assert_eq!(cases, vec!["alpha".to_string(), "beta_2".to_string()]);
        assert_eq!(
            imported_cases("gamma", "let x = super::alpha::scene();", &cases),
            vec!["alpha"]
        );
        assert_eq!(
            imported_cases("gamma", "super::super::beta_2::run(ctx)", &cases),
            vec!["beta_2"]
        );
        // Itself, a longer name and a shared module are not imports of a case.
        assert!(
            imported_cases(
                "alpha",
                "super::alpha::x; super::alphabet::y; super::common::z",
                &cases
            )
            .is_empty()
        );
    }

    #[test]
    fn text_rules_read_library_code_only() {
        let text = "//! x\nfn f() {}\n#[cfg(test)]\nmod tests {\n    fn g() { let beta = 1.0; }\n}\n";
        assert!(!library_part(text).contains(TEXT_RULES[0].pattern));
        assert!(library_part("let beta = 0.5;").contains(TEXT_RULES[0].pattern));
    }

    #[test]
    fn workspace_is_tidy() {
        check(&workspace_root()).unwrap();
    }

    #[test]
    fn manifests_are_read() {
        let text = r#"
[package]
name = "demcon-x"   # a comment
[dependencies]
demcon-core.workspace = true
faer = { version = "0.24" }
[dev-dependencies]
rand.workspace = true
[target.'cfg(unix)'.dependencies]
ron = "0.12"
[dependencies.demcon-graph]
workspace = true
[lints]
workspace = true
"#;
        let (name, d) = read_manifest(text);
        assert_eq!(name.as_deref(), Some("demcon-x"));
        let names: Vec<(&str, &str)> = d.iter().map(|d| (d.name.as_str(), d.section.as_str())).collect();
        assert_eq!(
            names,
            vec![
                ("demcon-core", "dependencies"),
                ("faer", "dependencies"),
                ("rand", "dev-dependencies"),
                ("ron", "dependencies"),
                ("demcon-graph", "dependencies"),
            ]
        );
    }

    #[test]
    fn forbidden_dependencies_are_named_with_their_rule() {
        assert!(
            check_dependencies(
                "demcon-thermal",
                &deps(&["demcon-core", "demcon-network", "rayon"])
            )
            .is_empty()
        );
        assert!(
            check_dependencies(
                "demcon-model",
                &deps(&[
                    "demcon-graph",
                    "demcon-packing",
                    "demcon-thermal",
                    "demcon-electric"
                ])
            )
            .is_empty()
        );
        let v = check_dependencies("demcon-thermal", &deps(&["demcon-electric"]));
        assert_eq!(v.len(), 1);
        let text = v[0].to_string();
        assert!(
            text.starts_with("demcon-thermal depends on demcon-electric (dependencies): siblings"),
            "{text}"
        );
        let v = check_dependencies("demcon-graph", &deps(&["demcon-packing"]));
        assert!(v[0].rule.contains("siblings"), "{}", v[0]);
        let v = check_dependencies("demcon-network", &deps(&["demcon-scene"]));
        assert!(v[0].rule.contains("point down only"), "{}", v[0]);
        let v = check_dependencies("demcon-post", &deps(&["demcon-thermal"]));
        assert!(v[0].rule.contains("plain slices"), "{}", v[0]);
        let v = check_dependencies("demcon-graph", &deps(&["faer"]));
        assert!(v[0].rule.contains("only demcon-network"), "{}", v[0]);
        let v = check_dependencies("demcon-post", &deps(&["ron"]));
        assert!(v[0].rule.contains("only demcon-scene"), "{}", v[0]);
        let v = check_dependencies("demcon-new", &deps(&["demcon-core"]));
        assert!(v[0].rule.contains("layer table"), "{}", v[0]);
        assert!(check_dependencies("demcon-scene", &deps(&["ron", "demcon-post"])).is_empty());
    }
}
