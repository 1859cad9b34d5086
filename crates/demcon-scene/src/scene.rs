//! A scene: the RON file read and checked once, and converted once into the plain plan the run
//! follows ([`Problem`]); parser messages in the scene's own words.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use demcon_core::ParticleSet;

use crate::config::{PackingConfig, SceneConfig};
use crate::convert::Problem;
use crate::error::SceneError;

/// A loaded scene: its configuration, checked once and converted once into the plain plan the
/// run follows ([`Problem`]), and the folder relative paths are resolved against. The
/// configuration is read-only: [`Scene::edit`] changes it and checks and converts it again, so
/// the plan never lags behind it.
#[derive(Debug, Clone)]
pub struct Scene {
    config: SceneConfig,
    /// Folder of the scene file.
    pub base_dir: PathBuf,
    problem: Problem,
    warnings: Vec<String>,
    /// The particles of a `Given` packing (shared by the scene's copies and edits).
    given: Option<Arc<ParticleSet>>,
}

impl Scene {
    /// Reads and parses a RON scene file; errors carry the line and column.
    /// The file must be UTF-8 (an error names the line and column of the first invalid byte).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
            path: path.into(),
            source,
        })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
            let col = 1 + good.iter().rev().take_while(|&&b| b != b'\n').count();
            SceneError::Parse {
                path: path.into(),
                line,
                col,
                message: "the file is not UTF-8 text (save the scene as UTF-8)".into(),
            }
        })?;
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, path, base_dir)
    }

    /// Parses RON text (`path` is only used in messages) and validates it. A UTF-8 byte-order
    /// mark is skipped; CR-LF and CR-only line endings count as line breaks.
    pub fn parse(text: &str, path: &Path, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let text = if text.contains('\r') {
            std::borrow::Cow::Owned(text.replace("\r\n", "\n").replace('\r', "\n"))
        } else {
            std::borrow::Cow::Borrowed(text)
        };
        let config: SceneConfig = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(&text)
            .map_err(|e| SceneError::Parse {
                path: path.into(),
                line: e.span.start.line,
                col: e.span.start.col,
                message: parse_message(&e.code),
            })?;
        Scene::from_config(config, base_dir)
    }

    /// A scene from a tree of values in the RON schema's shape (JSON's data model: a struct
    /// is an object, an enum variant `{"Variant": {...}}` or `"Variant"`, a tuple a list,
    /// `None` null): what the Python package's `demcon.Scene(dict)` hands over. An unknown key,
    /// a missing one or a wrong type is refused with its field path (`thermal.bcs[0].value`).
    pub fn from_value(value: serde_json::Value, base_dir: PathBuf) -> Result<Scene, SceneError> {
        Scene::from_config(config_of_value(value)?, base_dir)
    }

    /// A configuration from a tree of values (see [`Scene::from_value`]), not yet checked.
    pub fn config_of_value(value: serde_json::Value) -> Result<SceneConfig, SceneError> {
        config_of_value(value)
    }

    /// A scene from a configuration built in code (paths relative to `base_dir`): every value
    /// checked before any heavy work (`validate.rs`), then converted once.
    pub fn from_config(config: SceneConfig, base_dir: PathBuf) -> Result<Scene, SceneError> {
        Scene::checked(config, base_dir, None)
    }

    /// A scene on particles handed over in memory: `config.packing` becomes
    /// `Given { count, container }` (whatever it was), and the particles must lie in the
    /// container (as a packing file's must; radii > 0, coordinates finite).
    pub fn with_particles(
        mut config: SceneConfig,
        base_dir: PathBuf,
        particles: ParticleSet,
        container: crate::config::ContainerConfig,
    ) -> Result<Scene, SceneError> {
        let field = "packing.container";
        demcon_packing::check_inside(&particles, &crate::convert::container(&container, field)?)
            .map_err(|e| SceneError::invalid("packing", "the particles handed over", e.to_string()))?;
        // (no materials at all: the scene's own check says so)
        let out_of_range = |&(_, &k): &(usize, &u16)| usize::from(k) >= config.materials.len();
        if let Some((i, &k)) = particles.phases.iter().enumerate().find(out_of_range)
            && !config.materials.is_empty()
        {
            return Err(SceneError::invalid(
                &format!("phase[{i}]"),
                k,
                format!(
                    "a particle's phase is an index into `materials` (0..{})",
                    config.materials.len()
                ),
            ));
        }
        config.packing = PackingConfig::Given {
            count: particles.len(),
            container,
        };
        Scene::checked(config, base_dir, Some(Arc::new(particles)))
    }

    fn checked(
        config: SceneConfig,
        base_dir: PathBuf,
        given: Option<Arc<ParticleSet>>,
    ) -> Result<Scene, SceneError> {
        if given.is_none() && packs_given(&config.packing) {
            return Err(SceneError::invalid(
                "packing",
                "Given",
                "particles handed over in memory (the Python package's `demcon.Scene(..., packing=p)`); \
                 a scene file reads a packing with `File(path: ...)` or generates one",
            ));
        }
        let problem = crate::validate::validate(&config, &base_dir)?;
        let warnings = crate::validate::scene_warnings(&config);
        Ok(Scene {
            config,
            base_dir,
            problem,
            warnings,
            given,
        })
    }

    /// The scene with `change` applied to its configuration, checked and converted again
    /// (particles handed over stay).
    pub fn edit(self, change: impl FnOnce(&mut SceneConfig)) -> Result<Scene, SceneError> {
        let Scene {
            mut config,
            base_dir,
            given,
            ..
        } = self;
        change(&mut config);
        Scene::checked(config, base_dir, given)
    }

    /// The particles handed over by [`Scene::with_particles`].
    pub fn given_particles(&self) -> Option<&ParticleSet> {
        self.given.as_deref()
    }

    /// The configuration as written.
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The plain plan the run follows: model parameters, physics, post-processing.
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    /// What the scene asks for that is allowed but probably not meant (for `summary.json`).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// [`Scene::config_of_value`].
fn config_of_value(value: serde_json::Value) -> Result<SceneConfig, SceneError> {
    serde_path_to_error::deserialize::<_, SceneConfig>(value).map_err(|e| {
        let field = e.path().to_string();
        SceneError::Schema {
            field,
            message: scene_words(&e.into_inner().to_string()),
        }
    })
}

/// Whether a packing section is (or tiles) a `Given` one.
fn packs_given(p: &PackingConfig) -> bool {
    match p {
        PackingConfig::Given { .. } => true,
        PackingConfig::Tile { packing, .. } => packs_given(packing),
        PackingConfig::Generate { .. } | PackingConfig::File { .. } => false,
    }
}

/// The RON parser's message in the user's terms (no internal option names).
fn parse_message(code: &ron::error::Error) -> String {
    match code {
        ron::error::Error::ExceededRecursionLimit => {
            "the scene is nested too deeply (regions within regions, more than the parser's limit)".into()
        }
        other => scene_words(&other.to_string()),
    }
}

/// The scene's words for the parser's type names: what a user writes, not the Rust types
/// that read it (`in \`MaterialConfig\`` → `in a material (materials[..])`,
/// `\`RegionConfig::Difference\`` → `region \`Difference\``).
fn scene_words(message: &str) -> String {
    const NAMES: &[(&str, &str)] = &[
        ("SceneConfig", "the scene"),
        ("LinearSolverConfig", "`linear_solver`"),
        ("LinearMethodConfig", "`linear_solver.method`"),
        ("PackingConfig", "`packing`"),
        ("CarveRuleConfig", "`carve_rule`"),
        ("PhaseRuleConfig", "`phase_rule`"),
        ("ContainerConfig", "a container"),
        ("AxisConfig", "an axis"),
        ("RegionConfig", "a region"),
        ("ContactsConfig", "`contacts`"),
        ("CtConfig", "`c_t`"),
        ("SurfaceConfig", "a surface model"),
        ("MaterialConfig", "a material (`materials`)"),
        ("PhaseConfig", "a phase (`phases`)"),
        ("InterfaceResistanceConfig", "an interface (`interfaces`)"),
        ("CrackConfig", "a crack (`cracks`)"),
        ("DamageConfig", "a damage region (`damage`)"),
        ("CutContactsConfig", "`cut_contacts`"),
        ("InterfaceConfig", "`interface`"),
        ("FloatingConfig", "`floating`"),
        ("FaceConfig", "a face"),
        ("SelectorConfig", "a selector"),
        ("ThermalConfig", "`thermal`"),
        ("ThermalBcConfig", "a thermal boundary condition (`thermal.bcs`)"),
        ("SourceConfig", "a source (`thermal.sources`)"),
        ("TimeStepConfig", "a time step (`dt`)"),
        ("ImplicitSchemeConfig", "an implicit scheme"),
        ("ThermalSolverConfig", "a thermal solver (`thermal.solver`)"),
        ("CheckpointConfig", "`thermal.checkpoint`"),
        ("ElectricConfig", "`electric`"),
        ("ElectrodeConfig", "an electrode (`electric.electrodes`)"),
        ("ProbeMethodConfig", "a probe method"),
        ("HaloPhasesConfig", "`halo_phases`"),
        ("ProbeConfig", "a probe (`outputs.probes`)"),
        ("ProfileConfig", "a profile (`outputs.profiles`)"),
        ("OutputsConfig", "`outputs`"),
    ];
    let mut text = message.replace("in enum `", "in `").replace(
        "data did not match any variant of untagged enum TimedConfig",
        "expected a number or a time table [(t, value), …]",
    );
    for (rust, scene) in NAMES {
        // A variant first (`RegionConfig::Difference`, quoted or not), then the bare type.
        let variant = format!("{rust}::");
        while let Some(k) = text.find(&variant) {
            let quoted = k > 0 && text.as_bytes()[k - 1] == b'`';
            let start = k + variant.len();
            let end = text[start..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .map_or(text.len(), |e| start + e);
            let name = text[start..end].to_string();
            let what = scene.trim_start_matches("a ").trim_start_matches("an ");
            let (from, to) = if quoted && text[end..].starts_with('`') {
                (k - 1, end + 1)
            } else {
                (k, end)
            };
            text.replace_range(from..to, &format!("{what} `{name}`"));
        }
        text = text.replace(&format!("`{rust}`"), scene);
        text = text.replace(rust, scene);
    }
    text
}
