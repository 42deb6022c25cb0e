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
//! | `network`       | `[equilibrium]`, `[[viscous]]`, `[plastic]`, `[damper]` (below) |
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

//! ## `model = "network"`: the finite-strain network
//!
//! The parts of [`fem_core::material::network`], each an optional sub-table; at
//! least one is given. Their keys, units and bounds come from the law's own
//! parameter tables ([`fem_core::material::network::parameters`]):
//!
//! ```toml
//! [materials.gel]
//! model = "network"
//! poisson = 0.45                 # of every part, in (-1, 0.4999]
//! [materials.gel.equilibrium]    # absent: a fluid, like the seed's chain
//! energy = "exponential"         # or "neo-hookean" or "ogden"
//! E_MPa = 0.03                   # Young's modulus at small strain
//! stiffening = 0.5               # b of mu/(2b) [exp(b (I1bar - 3)) - 1] (exponential only)
//! # ogden only: sum_p 2 mu_p/alpha_p^2 sum_i (lbar_i^alpha_p - 1), mu_p = share_p mu
//! # alpha1 = 6.0                 # first term's exponent (required, nonzero)
//! # alpha2 = -2.0                # second term's exponent (default -2)
//! # share2 = 0.2                 # its share of mu (default 0: no second term)
//! # alpha3, share3               # a third term (defaults 4 and 0); share1 = 1 - share2 - share3
//! [materials.gel.equilibrium.mullins]  # Ogden-Roxburgh softening (optional)
//! r = 2.0                        # > 1: the most softening is 1 - 1/r
//! m_MPa = 0.001                  # its energy scale
//! beta = 0.1                     # its growth with the largest energy (default 0)
//! [[materials.gel.viscous]]      # a Maxwell network: Hencky spring and Newtonian flow
//! E_MPa = 0.02
//! tau_s = 3.0                    # relaxation time
//! [[materials.gel.viscous]]
//! E_MPa = 0.01
//! tau_s = 60.0
//! [materials.gel.plastic]        # a plastic network: the permanent set
//! E_MPa = 0.01                   # its Hencky spring
//! yield_MPa = 0.002              # uniaxial yield stress (von Mises)
//! hardening_MPa = 0.005          # linear isotropic hardening (default 0)
//! [materials.gel.damper]         # a parallel Newtonian damper
//! c_MPa_s = 0.005
//! ```
//!
//! A chain material runs beside network materials as its network equivalent
//! (the chain itself at small strain; [`fem_core::material::network::Network::from_chain`]).
//! `wagashi press` runs network materials on the Newton path (quasi-static, 3D,
//! plane strain or axisymmetric, with the protocol's plate and support).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use fem_core::material::law::ParameterSpec;
use fem_core::material::network::{Energy, Equilibrium, Mullins, Network, PlasticNetwork, ViscousNetwork, OGDEN_TERMS};
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
    /// The finite-strain network ([`fem_core::material::network`]): its parts in
    /// the sub-tables `[equilibrium]`, `[[viscous]]`, `[plastic]` and `[damper]` (module docs).
    Network,
}

impl Model {
    /// The model's name as the format spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            Model::Elastic => "elastic",
            Model::ThreeElement => "three-element",
            Model::FourElement => "four-element",
            Model::FiveElement => "five-element",
            Model::Network => "network",
        }
    }

    /// The model's parameter keys, `poisson` excepted, in the order of the table above.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            Model::Elastic => &["E_MPa"],
            Model::ThreeElement => &["E1_MPa", "c1_MPa_s", "c3_MPa_s"],
            Model::FourElement => &["E1_MPa", "c1_MPa_s", "E2_MPa", "c3_MPa_s"],
            Model::FiveElement => &["E1_MPa", "E2_MPa", "c1_MPa_s", "c2_MPa_s", "c3_MPa_s"],
            // Its parameters live in its sub-tables, each read through the law's
            // own table (fem_core::material::network::parameters).
            Model::Network => &[],
        }
    }
}

/// Ogden's keys in `[equilibrium]` (with `energy = "ogden"` only).
const OGDEN_KEYS: [&str; 5] = ["alpha1", "alpha2", "share2", "alpha3", "share3"];

/// The most viscous networks a network material's flat parameter keys reach
/// ([`NETWORK_KEYS`]).
pub const MAX_VISCOUS_NETWORKS: usize = 4;

/// A network material's parameters as flat keys, the paths of their sub-table
/// keys (`equilibrium.E_MPa`, `viscous[1].tau_s`): what identification names
/// and frees. [`MaterialSpec::parameter_keys`] gives those of a material's parts.
pub const NETWORK_KEYS: &[&str] = &[
    "equilibrium.E_MPa",
    "equilibrium.stiffening",
    "equilibrium.alpha1",
    "equilibrium.alpha2",
    "equilibrium.share2",
    "equilibrium.alpha3",
    "equilibrium.share3",
    "equilibrium.mullins.r",
    "equilibrium.mullins.m_MPa",
    "equilibrium.mullins.beta",
    "viscous[0].E_MPa",
    "viscous[0].tau_s",
    "viscous[1].E_MPa",
    "viscous[1].tau_s",
    "viscous[2].E_MPa",
    "viscous[2].tau_s",
    "viscous[3].E_MPa",
    "viscous[3].tau_s",
    "plastic.E_MPa",
    "plastic.yield_MPa",
    "plastic.hardening_MPa",
    "damper.c_MPa_s",
];

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
    /// `network`: the equilibrium network (`energy`, `E_MPa`, `stiffening`, and
    /// the sub-table `[mullins]`); absent: a fluid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<toml::Table>,
    /// `network`: the viscous networks, one `[[viscous]]` table each (`E_MPa`, `tau_s`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub viscous: Vec<toml::Table>,
    /// `network`: the plastic network (`E_MPa`, `yield_MPa`, `hardening_MPa`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic: Option<toml::Table>,
    /// `network`: the parallel damper (`c_MPa_s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damper: Option<toml::Table>,
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
            && (&self.equilibrium, &self.viscous, &self.plastic, &self.damper)
                == (&other.equilibrium, &other.viscous, &other.plastic, &other.damper)
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
            equilibrium: None,
            viscous: Vec::new(),
            plastic: None,
            damper: None,
            origin: None,
        }
    }

    /// A material of `model` with every parameter unknown: [`Self::new`], and for
    /// a network its default structure: an exponential equilibrium network with
    /// Ogden-Roxburgh softening (`beta` given as 0: the softening's scale does not
    /// grow with the largest energy), two viscous networks and a damper. Why this
    /// structure: the real double compressions this project holds (fungi steak)
    /// load on a J-shaped curve (the exponential energy), keep 0.8-0.9 of the
    /// first stroke's peak in the second at any speed (softening, not viscosity;
    /// a plastic set would reload to the same stress at the same strain), and
    /// drop fast on unloading (two viscous networks and a damper); design.md 3.6
    /// gives a 1D fit of this family.
    pub fn skeleton(model: Model) -> Self {
        let mut s = Self::new(model);
        if model == Model::Network {
            let mut eq = toml::Table::new();
            eq.insert("energy".into(), toml::Value::String("exponential".into()));
            let mut mullins = toml::Table::new();
            mullins.insert("beta".into(), toml::Value::Float(0.0));
            eq.insert("mullins".into(), toml::Value::Table(mullins));
            s.equilibrium = Some(eq);
            s.viscous = vec![toml::Table::new(), toml::Table::new()];
            s.damper = Some(toml::Table::new());
        }
        s
    }

    /// The spec of an engine material (every parameter given).
    pub fn from_material(material: &Material) -> Self {
        if let Some(net) = &material.network {
            return Self::from_network(net);
        }
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

    /// The spec of a network material.
    pub fn from_network(net: &Network) -> Self {
        let table = |pairs: &[(&str, f64)]| -> toml::Table {
            pairs.iter().map(|(k, v)| (k.to_string(), toml::Value::Float(*v))).collect()
        };
        let equilibrium = net.equilibrium.map(|eq| {
            let mut t = table(&[("E_MPa", eq.e_mpa)]);
            let energy = match eq.energy {
                Energy::NeoHookean => "neo-hookean",
                Energy::Exponential { stiffening } => {
                    t.insert("stiffening".into(), toml::Value::Float(stiffening));
                    "exponential"
                }
                Energy::Ogden { alpha, share } => {
                    t.insert("alpha1".into(), toml::Value::Float(alpha[0]));
                    for p in 1..OGDEN_TERMS {
                        if share[p] > 0.0 {
                            t.insert(format!("alpha{}", p + 1), toml::Value::Float(alpha[p]));
                            t.insert(format!("share{}", p + 1), toml::Value::Float(share[p]));
                        }
                    }
                    "ogden"
                }
            };
            t.insert("energy".into(), toml::Value::String(energy.into()));
            if let Some(m) = eq.mullins {
                t.insert(
                    "mullins".into(),
                    toml::Value::Table(table(&[("r", m.r), ("m_MPa", m.m_mpa), ("beta", m.beta)])),
                );
            }
            t
        });
        Self {
            poisson: Some(net.poisson),
            equilibrium,
            viscous: net.viscous.iter().map(|v| table(&[("E_MPa", v.e_mpa), ("tau_s", v.tau_s)])).collect(),
            plastic: net
                .plastic
                .map(|p| table(&[("E_MPa", p.e_mpa), ("yield_MPa", p.yield_mpa), ("hardening_MPa", p.hardening_mpa)])),
            damper: net.damper_mpa_s.map(|c| table(&[("c_MPa_s", c)])),
            ..Self::new(Model::Network)
        }
    }

    /// The network of a `network` material, read through the law's parameter
    /// tables: `Err((key path inside the material, cause))` for an unknown,
    /// missing, mistyped or out-of-bounds key. Needs `poisson`.
    pub fn to_network(&self) -> Result<Network, (String, String)> {
        use fem_core::material::network::parameters::{DAMPER, EQUILIBRIUM, MATERIAL, MULLINS, PLASTIC, VISCOUS};
        let poisson = self.poisson.ok_or_else(|| ("poisson".to_string(), "missing".to_string()))?;
        let mspec = MATERIAL[0];
        if !mspec.accepts(poisson) {
            return Err(("poisson".into(), format!("{poisson} is outside {} for a network", mspec.range())));
        }
        let equilibrium = match &self.equilibrium {
            None => None,
            Some(t) => {
                let energy = match t.get("energy") {
                    None => {
                        return Err(("equilibrium.energy".into(), "missing (neo-hookean, exponential or ogden)".into()))
                    }
                    Some(toml::Value::String(s)) if s == "neo-hookean" => "neo-hookean",
                    Some(toml::Value::String(s)) if s == "exponential" => "exponential",
                    Some(toml::Value::String(s)) if s == "ogden" => "ogden",
                    Some(other) => {
                        return Err((
                            "equilibrium.energy".into(),
                            format!("{other} is not an energy (neo-hookean, exponential or ogden)"),
                        ))
                    }
                };
                let mut allowed: Vec<&str> = vec!["energy", "E_MPa", "mullins"];
                match energy {
                    "exponential" => allowed.push("stiffening"),
                    "ogden" => allowed.extend(OGDEN_KEYS),
                    _ => {}
                }
                let values = read_table(t, EQUILIBRIUM, &allowed, "equilibrium")?;
                let e_mpa = values["E_MPa"];
                let energy = match energy {
                    "exponential" => Energy::Exponential { stiffening: values["stiffening"] },
                    "ogden" => {
                        let (s2, s3) = (values["share2"], values["share3"]);
                        if s2 + s3 >= 1.0 {
                            return Err((
                                "equilibrium.share2".into(),
                                format!(
                                    "share2 + share3 = {} must be under 1 (the first term takes the rest)",
                                    s2 + s3
                                ),
                            ));
                        }
                        let alpha = [values["alpha1"], values["alpha2"], values["alpha3"]];
                        let share = [1.0 - s2 - s3, s2, s3];
                        let min = fem_core::material::network::parameters::OGDEN_ALPHA_MIN;
                        if let Some(p) = (0..OGDEN_TERMS).find(|&p| share[p] > 0.0 && alpha[p].abs() < min) {
                            return Err((
                                format!("equilibrium.alpha{}", p + 1),
                                format!("{} must be nonzero (|alpha| >= {min}) for a term with a share", alpha[p]),
                            ));
                        }
                        Energy::Ogden { alpha, share }
                    }
                    _ => Energy::NeoHookean,
                };
                let mullins = match t.get("mullins") {
                    None => None,
                    Some(toml::Value::Table(m)) => {
                        let keys: Vec<&str> = MULLINS.iter().map(|s| s.key).collect();
                        let v = read_table(m, MULLINS, &keys, "equilibrium.mullins")?;
                        Some(Mullins { r: v["r"], m_mpa: v["m_MPa"], beta: v["beta"] })
                    }
                    Some(_) => return Err(("equilibrium.mullins".into(), "must be a table".into())),
                };
                Some(Equilibrium { energy, e_mpa, mullins })
            }
        };
        if self.viscous.len() > MAX_VISCOUS_NETWORKS {
            return Err((
                format!("viscous[{MAX_VISCOUS_NETWORKS}]"),
                format!("at most {MAX_VISCOUS_NETWORKS} viscous networks"),
            ));
        }
        let mut viscous = Vec::new();
        for (i, t) in self.viscous.iter().enumerate() {
            let keys: Vec<&str> = VISCOUS.iter().map(|s| s.key).collect();
            let v = read_table(t, VISCOUS, &keys, &format!("viscous[{i}]"))?;
            viscous.push(ViscousNetwork { e_mpa: v["E_MPa"], tau_s: v["tau_s"] });
        }
        let damper_mpa_s = match &self.damper {
            None => None,
            Some(t) => Some(read_table(t, DAMPER, &["c_MPa_s"], "damper")?["c_MPa_s"]),
        };
        let plastic = match &self.plastic {
            None => None,
            Some(t) => {
                let keys: Vec<&str> = PLASTIC.iter().map(|s| s.key).collect();
                let v = read_table(t, PLASTIC, &keys, "plastic")?;
                Some(PlasticNetwork { e_mpa: v["E_MPa"], yield_mpa: v["yield_MPa"], hardening_mpa: v["hardening_MPa"] })
            }
        };
        let net = Network { poisson, equilibrium, viscous, plastic, damper_mpa_s };
        net.validate().map_err(|e| ("".to_string(), e.to_string()))?;
        Ok(net)
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

    /// The parameter keys of this material: its model's, or, for a network, the
    /// [`NETWORK_KEYS`] of the parts it has (`poisson` not included).
    pub fn parameter_keys(&self) -> Vec<&'static str> {
        if self.model != Model::Network {
            return self.model.keys().to_vec();
        }
        NETWORK_KEYS.iter().copied().filter(|k| self.network_slot(k).is_some()).collect()
    }

    /// The sub-table and key of a network key whose part this material has:
    /// `(table path, key)`; the exponential's `stiffening` only with that energy,
    /// Mullins keys only with a `[mullins]` table.
    fn network_slot<'k>(&self, key: &'k str) -> Option<(Vec<String>, &'k str)> {
        let (path, leaf) = key.rsplit_once('.')?;
        let parts: Vec<String> = path.split('.').map(str::to_string).collect();
        self.network_table(&parts)?;
        let energy = |name: &str| matches!(self.equilibrium.as_ref().and_then(|t| t.get("energy")), Some(toml::Value::String(e)) if e == name);
        if leaf == "stiffening" && !(path == "equilibrium" && energy("exponential")) {
            return None;
        }
        if OGDEN_KEYS.contains(&leaf) && !(path == "equilibrium" && energy("ogden")) {
            return None;
        }
        Some((parts, leaf))
    }

    fn network_table(&self, parts: &[String]) -> Option<&toml::Table> {
        let first = parts.first()?;
        let mut table = if let Some(i) = first.strip_prefix("viscous[").and_then(|r| r.strip_suffix(']')) {
            self.viscous.get(i.parse::<usize>().ok()?)?
        } else if first == "equilibrium" {
            self.equilibrium.as_ref()?
        } else if first == "damper" {
            self.damper.as_ref()?
        } else if first == "plastic" {
            self.plastic.as_ref()?
        } else {
            return None;
        };
        for p in &parts[1..] {
            table = table.get(p)?.as_table()?;
        }
        Some(table)
    }

    /// Sets a network key of a part this material has; false otherwise.
    pub fn set_network_parameter(&mut self, key: &str, value: f64) -> bool {
        let Some((parts, leaf)) = self.network_slot(key) else { return false };
        let first = &parts[0];
        let mut table = if let Some(i) = first.strip_prefix("viscous[").and_then(|r| r.strip_suffix(']')) {
            let Ok(i) = i.parse::<usize>() else { return false };
            &mut self.viscous[i]
        } else if first == "equilibrium" {
            self.equilibrium.as_mut().expect("the slot exists")
        } else if first == "plastic" {
            self.plastic.as_mut().expect("the slot exists")
        } else {
            self.damper.as_mut().expect("the slot exists")
        };
        for p in &parts[1..] {
            table = table.get_mut(p).and_then(toml::Value::as_table_mut).expect("the slot exists");
        }
        table.insert(leaf.to_string(), toml::Value::Float(value));
        true
    }

    /// The value of parameter `key` (`poisson` included), if given.
    pub fn get(&self, key: &str) -> Option<f64> {
        if key == "poisson" {
            return self.poisson;
        }
        if self.model == Model::Network {
            let (parts, leaf) = self.network_slot(key)?;
            return match self.network_table(&parts)?.get(leaf)? {
                toml::Value::Float(x) => Some(*x),
                toml::Value::Integer(i) => Some(*i as f64),
                _ => None,
            };
        }
        self.parameters().into_iter().find(|(k, _)| *k == key).and_then(|(_, v)| v)
    }

    /// The model's keys (then `poisson`) that this material does not give;
    /// a network key with a default (Mullins' `beta`) is never missing.
    pub fn missing(&self) -> Vec<&'static str> {
        let mut out: Vec<&'static str> = self
            .parameter_keys()
            .into_iter()
            .filter(|k| self.get(k).is_none() && network_default(k).is_none())
            .collect();
        if self.poisson.is_none() {
            out.push("poisson");
        }
        out
    }

    /// The engine's chain, when every parameter of the model is given.
    pub fn to_rheology(&self) -> Result<Rheology, MissingParameter> {
        let need = |key: &'static str| self.get(key).ok_or(MissingParameter { key });
        Ok(match self.model {
            Model::Network => {
                if let Some(key) = self.missing().first() {
                    return Err(MissingParameter { key });
                }
                let net = self.to_network().map_err(|_| MissingParameter { key: "network" })?;
                Material::network(net).map_err(|_| MissingParameter { key: "network" })?.rheology
            }
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
        if self.model == Model::Network {
            self.poisson.ok_or(MissingParameter { key: "poisson" })?;
            // A bundle's materials were read through `validate`, which names the
            // key; here only an unchecked spec can fail.
            let net = self.to_network().map_err(|_| MissingParameter { key: "network" })?;
            return Material::network(net).map_err(|_| MissingParameter { key: "network" });
        }
        let rheology = self.to_rheology()?;
        let poisson = self.poisson.ok_or(MissingParameter { key: "poisson" })?;
        let damage = match (self.mullins_d_inf, self.mullins_strain_c) {
            (None, None) => None,
            (Some(d_inf), Some(strain_c)) => Some(MullinsDamage { d_inf, strain_c }),
            (Some(_), None) => return Err(MissingParameter { key: "mullins_strain_c" }),
            (None, Some(_)) => return Err(MissingParameter { key: "mullins_d_inf" }),
        };
        Ok(Material { rheology, poisson, damage, network: None })
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
        let network_tables =
            self.equilibrium.is_some() || !self.viscous.is_empty() || self.plastic.is_some() || self.damper.is_some();
        if self.model == Model::Network {
            if let Some((key, _)) = self.parameters().into_iter().find(|(_, v)| v.is_some()) {
                return Err(err(
                    key,
                    "not a key of the network model (its parts: [equilibrium], [[viscous]], [plastic], [damper])"
                        .into(),
                ));
            }
            if self.mullins_d_inf.is_some() || self.mullins_strain_c.is_some() {
                return Err(err("mullins_d_inf", "a network softens through [equilibrium.mullins]".into()));
            }
            // Every key is checked; absent parameters are unknowns (identification
            // fills them), so the parts are read with placeholders in their place.
            let mut filled = self.clone();
            for key in self.missing() {
                // A key given with a value of the wrong type is not absent: the
                // read below refuses it.
                let given = self
                    .network_slot(key)
                    .and_then(|(parts, leaf)| self.network_table(&parts).map(|t| t.contains_key(leaf)))
                    .unwrap_or(false);
                if key != "poisson" && !given {
                    filled.set_network_parameter(key, placeholder(key));
                }
            }
            if filled.poisson.is_none() {
                filled.poisson = Some(0.3);
            }
            return filled
                .to_network()
                .map(|_| ())
                .map_err(|(key, cause)| err(if key.is_empty() { "model" } else { &key }, cause));
        } else if network_tables {
            let key = if self.equilibrium.is_some() {
                "equilibrium"
            } else if self.damper.is_some() {
                "damper"
            } else if self.plastic.is_some() {
                "plastic"
            } else {
                "viscous"
            };
            return Err(err(
                key,
                format!("only a network material has it (model = \"network\", not {})", self.model.as_str()),
            ));
        }
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

/// The default of a network key ([`NETWORK_KEYS`]) from the law's tables, if it has one.
fn network_default(key: &str) -> Option<f64> {
    use fem_core::material::network::parameters::{DAMPER, EQUILIBRIUM, MULLINS, PLASTIC, VISCOUS};
    let (path, leaf) = key.rsplit_once('.')?;
    let table = match path {
        "equilibrium" => EQUILIBRIUM,
        "equilibrium.mullins" => MULLINS,
        "damper" => DAMPER,
        "plastic" => PLASTIC,
        _ if path.starts_with("viscous[") => VISCOUS,
        _ => return None,
    };
    table.iter().find(|s| s.key == leaf)?.default
}

/// A value inside a network key's bounds, standing for an unknown while the
/// rest of the material is checked.
fn placeholder(key: &str) -> f64 {
    if key.ends_with(".r") {
        2.0
    } else {
        1.0
    }
}

/// Reads the keys of one sub-table through the law's parameter `table`: each
/// key in `allowed` (the non-numeric ones are the caller's), numbers within
/// their bounds, required ones present, defaults filled in.
fn read_table(
    t: &toml::Table,
    table: &[ParameterSpec],
    allowed: &[&str],
    prefix: &str,
) -> Result<BTreeMap<&'static str, f64>, (String, String)> {
    for key in t.keys() {
        if !allowed.contains(&key.as_str()) {
            return Err((format!("{prefix}.{key}"), format!("not a key here (its keys: {})", allowed.join(", "))));
        }
    }
    let mut out = BTreeMap::new();
    for spec in table.iter().filter(|s| allowed.contains(&s.key)) {
        let value = match t.get(spec.key) {
            None => match spec.default {
                Some(d) => d,
                None => {
                    return Err((
                        format!("{prefix}.{}", spec.key),
                        format!("missing ({}, {})", spec.meaning, spec.unit),
                    ))
                }
            },
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(i)) => *i as f64,
            Some(other) => return Err((format!("{prefix}.{}", spec.key), format!("{other} is not a number"))),
        };
        if !spec.accepts(value) {
            return Err((format!("{prefix}.{}", spec.key), format!("{value} is outside {}", spec.range())));
        }
        out.insert(spec.key, value);
    }
    Ok(out)
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
