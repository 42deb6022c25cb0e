//! `[materials.NAME]`: a rheological model and its parameters, and the
//! `--materials FILE` TOML that holds only such tables.
//!
//! Key sets (besides `model` and `poisson`, Poisson's ratio in (-1, 0.5)):
//!
//! | model           | keys                                               |
//! |-----------------|----------------------------------------------------|
//! | `elastic`       | `E_MPa`                                            |
//! | `three-element` | `E1_MPa, c1_MPa_s, c3_MPa_s`                       |
//! | `four-element`  | `E1_MPa, c1_MPa_s, E2_MPa, c3_MPa_s` (E2 the series spring) |
//! | `five-element`  | `E1_MPa, E2_MPa, c1_MPa_s, c2_MPa_s, c3_MPa_s`     |
//!
//! Every parameter is optional when reading, so that identification can take a
//! material that gives only its model and the parameters to hold fixed; a key
//! outside the model's set is refused. Converting to an engine material
//! ([`MaterialSpec::to_material`]) needs all of them.
//!
//! Any model may also carry a Mullins-type stress softening (the engine's
//! continuum damage, [`fem_core::material::MullinsDamage`]; an extension of
//! wagashi, not in experiment-format.md): `mullins_d_inf` (saturated damage, in
//! [0, 0.8]) and `mullins_strain_c` (characteristic equivalent strain, > 0),
//! both or neither. The chain then acts on `(1 - d) e` with `d = mullins_d_inf
//! (1 - exp(-alpha / mullins_strain_c))` and `alpha` the largest equivalent
//! strain so far. They are fixed values, not among the model's parameters
//! (nothing identifies them; `wagashi fit` and the diagnosis difference such
//! trials, since the damage runs without forward sensitivities), and `wagashi press`
//! runs them on the quasi-static integrator, with the constrained plate or with
//! contact tools, also with machine compliance (not with a material-point effect).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use fem_core::material::{Material, MaterialError, MullinsDamage, Rheology};
use serde::{Deserialize, Serialize};

use crate::error::BundleError;
use crate::source_map::SourceMap;

/// A rheological model of the seed's Fig. 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// Hookean solid: `E_MPa`.
    Elastic,
    /// A Voigt element `(E1, c1)` in series with a dashpot `c3`.
    ThreeElement,
    /// A spring `E2`, a Voigt element `(E1, c1)` and a dashpot `c3` in series.
    FourElement,
    /// Two Voigt elements `(E1, c1)`, `(E2, c2)` and a dashpot `c3` in series.
    FiveElement,
}

impl Model {
    /// The model's name as the format spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            Model::Elastic => "elastic",
            Model::ThreeElement => "three-element",
            Model::FourElement => "four-element",
            Model::FiveElement => "five-element",
        }
    }

    /// The model's parameter keys, `poisson` excepted, in the order of the table above.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            Model::Elastic => &["E_MPa"],
            Model::ThreeElement => &["E1_MPa", "c1_MPa_s", "c3_MPa_s"],
            Model::FourElement => &["E1_MPa", "c1_MPa_s", "E2_MPa", "c3_MPa_s"],
            Model::FiveElement => &["E1_MPa", "E2_MPa", "c1_MPa_s", "c2_MPa_s", "c3_MPa_s"],
        }
    }
}

/// One material as a bundle writes it. Parameters are optional (see the module docs).
///
/// Equality compares the model and the values only, not where the table was read.
/// Build one with [`MaterialSpec::new`] (or [`MaterialSpec::from_material`]) and
/// set the fields: a hidden field remembers where a table was read, for messages.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// The rheological model.
    pub model: Model,
    /// Poisson's ratio, in (-1, 0.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    /// `elastic`: Young's modulus [MPa].
    #[serde(rename = "E_MPa", default, skip_serializing_if = "Option::is_none")]
    pub e_mpa: Option<f64>,
    /// Spring of the first Voigt element [MPa].
    #[serde(rename = "E1_MPa", default, skip_serializing_if = "Option::is_none")]
    pub e1_mpa: Option<f64>,
    /// Five-element: spring of the second Voigt element; four-element: the series spring [MPa].
    #[serde(rename = "E2_MPa", default, skip_serializing_if = "Option::is_none")]
    pub e2_mpa: Option<f64>,
    /// Dashpot of the first Voigt element [MPa s].
    #[serde(rename = "c1_MPa_s", default, skip_serializing_if = "Option::is_none")]
    pub c1_mpa_s: Option<f64>,
    /// Five-element: dashpot of the second Voigt element [MPa s].
    #[serde(rename = "c2_MPa_s", default, skip_serializing_if = "Option::is_none")]
    pub c2_mpa_s: Option<f64>,
    /// The series dashpot [MPa s].
    #[serde(rename = "c3_MPa_s", default, skip_serializing_if = "Option::is_none")]
    pub c3_mpa_s: Option<f64>,
    /// Mullins-type damage: the saturated damage `d_inf`, in [0, 0.8] (module docs).
    #[serde(rename = "mullins_d_inf", default, skip_serializing_if = "Option::is_none")]
    pub mullins_d_inf: Option<f64>,
    /// Mullins-type damage: the characteristic equivalent strain, > 0 (module docs).
    #[serde(rename = "mullins_strain_c", default, skip_serializing_if = "Option::is_none")]
    pub mullins_strain_c: Option<f64>,
    /// Where the table was read: the file's map and the table's key path.
    #[serde(skip)]
    pub(crate) origin: Option<Origin>,
}

/// Where a material table was read: the file's map and the table's key path.
#[derive(Clone)]
pub(crate) struct Origin {
    pub(crate) map: Arc<SourceMap>,
    pub(crate) table: String,
}

impl std::fmt::Debug for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{} [{}]", self.map.file().display(), self.map.line(&self.table), self.table)
    }
}

impl PartialEq for MaterialSpec {
    fn eq(&self, other: &Self) -> bool {
        self.model == other.model
            && self.poisson == other.poisson
            && self.parameters() == other.parameters()
            && (self.mullins_d_inf, self.mullins_strain_c) == (other.mullins_d_inf, other.mullins_strain_c)
    }
}

/// A parameter the engine needs that a material does not give.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingParameter {
    /// The missing key, e.g. `c3_MPa_s` or `poisson`.
    pub key: &'static str,
}

impl MaterialSpec {
    /// A material with only its model; every parameter unknown.
    pub fn new(model: Model) -> Self {
        Self {
            model,
            poisson: None,
            e_mpa: None,
            e1_mpa: None,
            e2_mpa: None,
            c1_mpa_s: None,
            c2_mpa_s: None,
            c3_mpa_s: None,
            mullins_d_inf: None,
            mullins_strain_c: None,
            origin: None,
        }
    }

    /// The spec of an engine material (every parameter given).
    pub fn from_material(material: &Material) -> Self {
        let mut s = match material.rheology {
            Rheology::Elastic { e_mpa } => Self { e_mpa: Some(e_mpa), ..Self::new(Model::Elastic) },
            Rheology::ThreeElement { e1_mpa, c1_mpa_s, c3_mpa_s } => Self {
                e1_mpa: Some(e1_mpa),
                c1_mpa_s: Some(c1_mpa_s),
                c3_mpa_s: Some(c3_mpa_s),
                ..Self::new(Model::ThreeElement)
            },
            Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s } => Self {
                e1_mpa: Some(e1_mpa),
                c1_mpa_s: Some(c1_mpa_s),
                e2_mpa: Some(e2_mpa),
                c3_mpa_s: Some(c3_mpa_s),
                ..Self::new(Model::FourElement)
            },
            Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c2_mpa_s, c3_mpa_s } => Self {
                e1_mpa: Some(e1_mpa),
                e2_mpa: Some(e2_mpa),
                c1_mpa_s: Some(c1_mpa_s),
                c2_mpa_s: Some(c2_mpa_s),
                c3_mpa_s: Some(c3_mpa_s),
                ..Self::new(Model::FiveElement)
            },
        };
        s.poisson = Some(material.poisson);
        if let Some(d) = material.damage {
            s.mullins_d_inf = Some(d.d_inf);
            s.mullins_strain_c = Some(d.strain_c);
        }
        s
    }

    /// Every parameter key with its value, whether or not it belongs to the model.
    pub fn parameters(&self) -> [(&'static str, Option<f64>); 6] {
        [
            ("E_MPa", self.e_mpa),
            ("E1_MPa", self.e1_mpa),
            ("E2_MPa", self.e2_mpa),
            ("c1_MPa_s", self.c1_mpa_s),
            ("c2_MPa_s", self.c2_mpa_s),
            ("c3_MPa_s", self.c3_mpa_s),
        ]
    }

    /// The value of parameter `key` (`poisson` included), if given.
    pub fn get(&self, key: &str) -> Option<f64> {
        if key == "poisson" {
            return self.poisson;
        }
        self.parameters().into_iter().find(|(k, _)| *k == key).and_then(|(_, v)| v)
    }

    /// The model's keys (then `poisson`) that this material does not give.
    pub fn missing(&self) -> Vec<&'static str> {
        let mut out: Vec<&'static str> = self.model.keys().iter().copied().filter(|k| self.get(k).is_none()).collect();
        if self.poisson.is_none() {
            out.push("poisson");
        }
        out
    }

    /// The engine's chain, when every parameter of the model is given.
    pub fn to_rheology(&self) -> Result<Rheology, MissingParameter> {
        let need = |key: &'static str| self.get(key).ok_or(MissingParameter { key });
        Ok(match self.model {
            Model::Elastic => Rheology::Elastic { e_mpa: need("E_MPa")? },
            Model::ThreeElement => Rheology::ThreeElement {
                e1_mpa: need("E1_MPa")?,
                c1_mpa_s: need("c1_MPa_s")?,
                c3_mpa_s: need("c3_MPa_s")?,
            },
            Model::FourElement => Rheology::FourElement {
                e1_mpa: need("E1_MPa")?,
                c1_mpa_s: need("c1_MPa_s")?,
                e2_mpa: need("E2_MPa")?,
                c3_mpa_s: need("c3_MPa_s")?,
            },
            Model::FiveElement => Rheology::FiveElement {
                e1_mpa: need("E1_MPa")?,
                e2_mpa: need("E2_MPa")?,
                c1_mpa_s: need("c1_MPa_s")?,
                c2_mpa_s: need("c2_MPa_s")?,
                c3_mpa_s: need("c3_MPa_s")?,
            },
        })
    }

    /// The engine material (not yet validated by the engine), when every parameter
    /// of the model and `poisson` are given.
    pub fn to_material(&self) -> Result<Material, MissingParameter> {
        let rheology = self.to_rheology()?;
        let poisson = self.poisson.ok_or(MissingParameter { key: "poisson" })?;
        let damage = match (self.mullins_d_inf, self.mullins_strain_c) {
            (None, None) => None,
            (Some(d_inf), Some(strain_c)) => Some(MullinsDamage { d_inf, strain_c }),
            (Some(_), None) => return Err(MissingParameter { key: "mullins_strain_c" }),
            (None, Some(_)) => return Err(MissingParameter { key: "mullins_d_inf" }),
        };
        Ok(Material { rheology, poisson, damage })
    }

    /// The file this table was read from and the line of `key` in it (of the
    /// table when the key is absent), when known.
    pub fn location(&self, key: &str) -> Option<(&Path, usize)> {
        let o = self.origin.as_ref()?;
        let full = if key.is_empty() { o.table.clone() } else { format!("{}.{key}", o.table) };
        Some((o.map.file(), o.map.line(&full)))
    }

    /// Refuses keys outside the model's set, non-positive or non-finite
    /// parameters and a Poisson ratio outside (-1, 0.5). `name` is the table's
    /// name; `fallback` locates the error when the table's origin is unknown.
    pub(crate) fn validate(&self, name: &str, fallback: &SourceMap, fallback_field: &str) -> Result<(), BundleError> {
        let err = |key: &str, cause: String| match &self.origin {
            Some(o) => o.map.invalid(&format!("{}.{key}", o.table), cause),
            None => BundleError::Invalid {
                file: fallback.file().to_path_buf(),
                line: fallback.line(fallback_field),
                field: format!("materials.{name}.{key}"),
                cause,
            },
        };
        let keys = self.model.keys();
        for (key, value) in self.parameters() {
            let Some(v) = value else { continue };
            if !keys.contains(&key) {
                return Err(err(
                    key,
                    format!(
                        "not a parameter of the {} model (its keys: {}, poisson)",
                        self.model.as_str(),
                        keys.join(", ")
                    ),
                ));
            }
            if !(v.is_finite() && v > 0.0) {
                let what = if key.starts_with('E') { "a modulus" } else { "a viscosity" };
                return Err(err(key, format!("{v} is not {what} > 0")));
            }
        }
        if let Some(nu) = self.poisson {
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return Err(err("poisson", format!("{nu} is outside (-1, 0.5)")));
            }
        }
        match (self.mullins_d_inf, self.mullins_strain_c) {
            (None, None) => {}
            (Some(_), None) => return Err(err("mullins_d_inf", "needs mullins_strain_c too".into())),
            (None, Some(_)) => return Err(err("mullins_strain_c", "needs mullins_d_inf too".into())),
            (Some(d_inf), Some(strain_c)) => {
                if let Err(MaterialError::DamageOutOfRange { name, value, range }) = MullinsDamage::new(d_inf, strain_c)
                {
                    return Err(err(&format!("mullins_{name}"), format!("{value} is outside {range}")));
                }
            }
        }
        Ok(())
    }
}

/// A `--materials FILE`: only `[materials.NAME]` tables.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialsFile {
    #[serde(default)]
    materials: BTreeMap<String, MaterialSpec>,
}

/// Reads a `--materials FILE` TOML holding `[materials.NAME]` tables, each checked
/// as in a bundle. Errors name the file, the line and the key. Give the result to
/// [`super::read_bundle_with`]; each material remembers where it was read.
pub fn read_materials_file(path: impl AsRef<Path>) -> Result<BTreeMap<String, MaterialSpec>, BundleError> {
    let path = path.as_ref();
    let text =
        crate::input::read_to_string(path).map_err(|source| BundleError::Read { file: path.to_path_buf(), source })?;
    let map = Arc::new(SourceMap::parse(path, &text)?);
    let parsed: MaterialsFile = toml::from_str(&text).map_err(|e| map.toml_error(&e))?;
    let mut out = parsed.materials;
    for (name, spec) in out.iter_mut() {
        spec.origin = Some(Origin { map: map.clone(), table: format!("materials.{name}") });
        spec.validate(name, &map, "materials")?;
    }
    Ok(out)
}

pub(crate) fn attach_origins(materials: &mut BTreeMap<String, MaterialSpec>, map: &Arc<SourceMap>) {
    for (name, spec) in materials.iter_mut() {
        spec.origin = Some(Origin { map: map.clone(), table: format!("materials.{name}") });
    }
}
