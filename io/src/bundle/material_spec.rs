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
//! | `network`       | `[equilibrium]` and the parts `[[viscous]]`, `[plastic]`, `[[flow]]`, `[bingham]`, `[damper]`, `[[dual]]` (below) |
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
//! least one is given. The equilibrium network's keys come from its table
//! ([`fem_core::material::network::parameters`]); every other sub-table is a
//! registered part ([`fem_core::material::network::PARTS`]), read through its
//! kind's table: its name, how many a material may hold (a single `[table]`,
//! or `[[table]]` entries), its keys, units, bounds and defaults. A part added
//! to the registry is read, written and fitted here with no change to this file.
//!
//! ```toml
//! [materials.gel]
//! model = "network"
//! poisson = 0.45                 # of every part, in (-1, 0.4999]
//! kinematics = "finite"          # the default; "small": every part on the small strain
//!                                # (neo-Hookean equilibrium without softening, viscous
//!                                # networks and the damper only: the seed's chain exactly)
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
//! kinematic_MPa = 0.0            # linear kinematic (Prager) hardening (default 0)
//! [[materials.gel.flow]]         # a Maxwell network with power-law (Norton) flow of its shear
//! E_MPa = 0.01
//! stress_MPa = 0.004             # the equivalent stress flowing at a strain rate of 1/s
//! exponent = 2.0                 # n >= 1 of the rate (1: Newtonian; default 1)
//! [materials.gel.bingham]        # a Maxwell network flowing only above a yield stress
//! E_MPa = 0.01
//! yield_MPa = 0.001              # equivalent yield stress of the flow
//! viscosity_MPa_s = 0.05         # plastic viscosity: sigma = sigma_y + eta d(eps)/dt
//! [materials.gel.damper]         # a parallel Newtonian damper
//! c_MPa_s = 0.005
//! [[materials.gel.dual]]         # up to two: a Maxwell network with a dual viscosity
//! E_MPa = 0.01
//! tau_load_s = 3.0               # relaxation time while its spring loads or holds
//! tau_unload_s = 0.5             # relaxation time while it unloads (each step takes
//!                                # the direction of the step before)
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
use fem_core::material::network::{
    energy_keys, parameters, part, Energy, Equilibrium, Mullins, Network, NetworkError, PartKind, Strain, ENERGIES,
    OGDEN_TERMS, PARTS,
};
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
    /// The finite-strain network ([`fem_core::material::network`]): the
    /// sub-table `[equilibrium]` and one per part (module docs).
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

/// A network material's parameters as flat keys, the paths of their sub-table
/// keys (`equilibrium.E_MPa`, `viscous[1].tau_s`): what identification names
/// and frees ([`parameters::flat_keys`]). [`MaterialSpec::parameter_keys`]
/// gives those of a material's parts.
pub fn network_keys() -> &'static [&'static str] {
    parameters::flat_keys()
}

/// One material as a bundle writes it. Parameters are optional (see the module docs).
///
/// Equality compares the model and the values only, not where the table was read.
/// Build one with [`MaterialSpec::new`] (or [`MaterialSpec::from_material`]) and
/// set the fields: a hidden field remembers where a table was read, for messages.
///
/// Unknown keys are kept (in [`Self::parts`]) and refused by the reader with
/// their line, naming the model's keys.
#[derive(Debug, Clone, Serialize, Deserialize)]
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
    /// `network`: the parts, by sub-table name: a table (`[plastic]`) or an
    /// array of tables (`[[viscous]]`), each of a registered kind
    /// ([`fem_core::material::network::PARTS`]). Any other key of the table
    /// lands here too, for the reader to refuse.
    #[serde(flatten, default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parts: BTreeMap<String, toml::Value>,
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
            && (&self.equilibrium, &self.parts) == (&other.equilibrium, &other.parts)
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
            parts: BTreeMap::new(),
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
            s.parts.insert(
                "viscous".into(),
                toml::Value::Array(vec![
                    toml::Value::Table(toml::Table::new()),
                    toml::Value::Table(toml::Table::new()),
                ]),
            );
            s.parts.insert("damper".into(), toml::Value::Table(toml::Table::new()));
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
        let mut parts: BTreeMap<String, toml::Value> = BTreeMap::new();
        for p in &net.parts {
            let kind = p.kind();
            let pairs: Vec<(&str, f64)> = kind.parameters.iter().map(|s| s.key).zip(p.values()).collect();
            let t = toml::Value::Table(table(&pairs));
            if kind.max_count == 1 {
                parts.insert(kind.table.into(), t);
            } else {
                match parts.entry(kind.table.into()).or_insert_with(|| toml::Value::Array(Vec::new())) {
                    toml::Value::Array(a) => a.push(t),
                    _ => unreachable!("a kind of several parts is written as an array"),
                }
            }
        }
        if net.strain != Strain::Finite {
            parts.insert(KINEMATICS.into(), toml::Value::String(net.strain.name().into()));
        }
        Self { poisson: Some(net.poisson), equilibrium, parts, ..Self::new(Model::Network) }
    }

    /// The network of a `network` material, read through the law's parameter
    /// tables: `Err((key path inside the material, cause))` for an unknown,
    /// missing, mistyped or out-of-bounds key. Needs `poisson`.
    pub fn to_network(&self) -> Result<Network, (String, String)> {
        use parameters::{EQUILIBRIUM, MATERIAL, MULLINS};
        let poisson = self.poisson.ok_or_else(|| ("poisson".to_string(), "missing".to_string()))?;
        let mspec = MATERIAL[0];
        if !mspec.accepts(poisson) {
            return Err(("poisson".into(), format!("{poisson} is outside {} for a network", mspec.range())));
        }
        let mut net = Network::new(poisson);
        if let Some(v) = self.parts.get(KINEMATICS) {
            let names = Strain::NAMES.iter().map(|(n, _)| format!("\"{n}\"")).collect::<Vec<_>>().join(", ");
            let strain = v.as_str().and_then(|s| Strain::NAMES.iter().find(|(n, _)| *n == s)).map(|(_, k)| *k);
            net.strain =
                strain.ok_or_else(|| (KINEMATICS.to_string(), format!("{v} is not a kinematics ({names})")))?;
        }
        if let Some(t) = &self.equilibrium {
            let energies = ENERGIES.join(", ");
            let energy = match t.get("energy") {
                None => return Err(("equilibrium.energy".into(), format!("missing ({energies})"))),
                Some(toml::Value::String(s)) if energy_keys(s).is_some() => s.as_str(),
                Some(other) => {
                    return Err(("equilibrium.energy".into(), format!("{other} is not an energy ({energies})")))
                }
            };
            let mut allowed: Vec<&str> = vec!["energy", "mullins"];
            allowed.extend(energy_keys(energy).expect("a known energy"));
            let values = read_table(t, EQUILIBRIUM, &allowed, "equilibrium")?;
            let e_mpa = values["E_MPa"];
            let energy = match energy {
                "exponential" => Energy::Exponential { stiffening: values["stiffening"] },
                "ogden" => {
                    let (s2, s3) = (values["share2"], values["share3"]);
                    if s2 + s3 >= 1.0 {
                        return Err((
                            "equilibrium.share2".into(),
                            format!("share2 + share3 = {} must be under 1 (the first term takes the rest)", s2 + s3),
                        ));
                    }
                    let alpha = [values["alpha1"], values["alpha2"], values["alpha3"]];
                    let share = [1.0 - s2 - s3, s2, s3];
                    let min = parameters::OGDEN_ALPHA_MIN;
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
            net = net.with_equilibrium(Equilibrium { energy, e_mpa, mullins });
        }
        for name in self.parts.keys() {
            if name != KINEMATICS && part::kind(name).is_none() {
                return Err((name.clone(), format!("not a key of the network model (its parts: {})", part_list())));
            }
        }
        for kind in PARTS {
            let tables = self.part_tables(kind.table).map_err(|cause| (kind.table.to_string(), cause))?;
            if tables.len() > kind.max_count {
                return Err((
                    format!("{}[{}]", kind.table, kind.max_count),
                    format!("at most {} {} parts", kind.max_count, kind.table),
                ));
            }
            for (i, t) in tables.iter().enumerate() {
                let keys: Vec<&str> = kind.parameters.iter().map(|s| s.key).collect();
                let prefix = kind.flat_key(i, "");
                let v = read_table(t, kind.parameters, &keys, prefix.trim_end_matches('.'))?;
                let values: Vec<f64> = keys.iter().map(|k| v[k]).collect();
                net.parts.push((kind.build)(&values));
            }
        }
        net.validate().map_err(|e| {
            let key = if matches!(e, NetworkError::NoSmallStrainForm { .. }) { KINEMATICS } else { "" };
            (key.to_string(), e.to_string())
        })?;
        Ok(net)
    }

    /// The tables of the part sub-table `name`: none, the one table, or the
    /// array's; `Err(cause)` for any other value.
    fn part_tables(&self, name: &str) -> Result<Vec<&toml::Table>, String> {
        match self.parts.get(name) {
            None => Ok(Vec::new()),
            Some(toml::Value::Table(t)) => Ok(vec![t]),
            Some(toml::Value::Array(a)) => a
                .iter()
                .map(|v| v.as_table().ok_or_else(|| format!("{v} is not a table")))
                .collect::<Result<Vec<_>, _>>(),
            Some(other) => Err(format!("{other} is not a table")),
        }
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
    /// [`network_keys`] of the parts it has (`poisson` not included).
    pub fn parameter_keys(&self) -> Vec<&'static str> {
        if self.model != Model::Network {
            return self.model.keys().to_vec();
        }
        network_keys().iter().copied().filter(|k| self.network_slot(k).is_some()).collect()
    }

    /// The sub-table and key of a network key whose part this material has:
    /// `(table path, key)`; an energy's keys only with that energy, Mullins keys
    /// only with a `[mullins]` table.
    fn network_slot<'k>(&self, key: &'k str) -> Option<(Vec<String>, &'k str)> {
        let (path, leaf) = key.rsplit_once('.')?;
        parameters::spec_of(key)?;
        let parts: Vec<String> = path.split('.').map(str::to_string).collect();
        self.network_table(&parts)?;
        if path == "equilibrium" {
            let energy = self.equilibrium.as_ref().and_then(|t| t.get("energy")).and_then(toml::Value::as_str);
            if !energy.and_then(energy_keys).is_some_and(|keys| keys.contains(&leaf)) {
                return None;
            }
        }
        Some((parts, leaf))
    }

    /// The part sub-table `name` or `name[i]`: its kind and index.
    fn part_slot(first: &str) -> Option<(&'static PartKind, usize)> {
        let (name, index) = match first.split_once('[') {
            Some((name, rest)) => (name, rest.strip_suffix(']')?.parse::<usize>().ok()?),
            None => (first, 0),
        };
        let kind = part::kind(name)?;
        ((kind.max_count > 1) == first.contains('[')).then_some((kind, index))
    }

    fn network_table(&self, parts: &[String]) -> Option<&toml::Table> {
        let first = parts.first()?;
        let mut table = if first == "equilibrium" {
            self.equilibrium.as_ref()?
        } else {
            let (kind, index) = Self::part_slot(first)?;
            *self.part_tables(kind.table).ok()?.get(index)?
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
        let mut table = if first == "equilibrium" {
            self.equilibrium.as_mut().expect("the slot exists")
        } else {
            let (kind, index) = Self::part_slot(first).expect("the slot exists");
            match self.parts.get_mut(kind.table).expect("the slot exists") {
                toml::Value::Table(t) => t,
                toml::Value::Array(a) => a[index].as_table_mut().expect("the slot exists"),
                _ => return false,
            }
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
    /// parameters, parameters above [`MAX_CHAIN_PARAMETER`] and a Poisson
    /// ratio outside (-1, 0.5). `name` is the table's
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
        let network_tables = self.equilibrium.is_some() || !self.parts.is_empty();
        if self.model == Model::Network {
            if let Some((key, _)) = self.parameters().into_iter().find(|(_, v)| v.is_some()) {
                return Err(err(key, format!("not a key of the network model (its parts: {})", part_list())));
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
            let key = match self.parts.keys().next() {
                _ if self.equilibrium.is_some() => "equilibrium",
                Some(key) if part::kind(key).is_some() => key.as_str(),
                Some(key) => {
                    return Err(err(
                        key,
                        format!(
                            "not a key of the {} model (its keys: {}, poisson)",
                            self.model.as_str(),
                            self.model.keys().join(", ")
                        ),
                    ))
                }
                None => unreachable!("a network table is present"),
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
            let what = if key.starts_with('E') { "a modulus" } else { "a viscosity" };
            if !(v.is_finite() && v > 0.0) {
                return Err(err(key, format!("{v} is not {what} > 0")));
            }
            if v > MAX_CHAIN_PARAMETER {
                return Err(err(
                    key,
                    format!(
                        "{v:e} is larger than the {MAX_CHAIN_PARAMETER:e} {what} may be: the solver's squared norms of \
                         such a stiffness overflow double precision"
                    ),
                ));
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

/// The largest modulus [MPa] or viscosity [MPa s] of a chain model (elastic,
/// three-, four- and five-element) that a run can carry: a step's residual and
/// energy norms square the stiffness times the displacement, and double
/// precision ends at 1.8e308 (a block run with E1 = 1e150 MPa still ends
/// finite; with 1e200 MPa the first step overflows). Any food is 90 orders of
/// magnitude below it.
pub const MAX_CHAIN_PARAMETER: f64 = 1e100;

/// The default of a network key ([`network_keys`]) from the law's tables, if it has one.
fn network_default(key: &str) -> Option<f64> {
    parameters::spec_of(key)?.0.default
}

/// A value inside a network key's bounds, standing for an unknown while the
/// rest of the material is checked: the low end of its fit range.
fn placeholder(key: &str) -> f64 {
    parameters::spec_of(key).map_or(1.0, |(s, _)| if s.accepts(s.fit.lower) { s.fit.lower } else { s.fit.upper })
}

/// The network's sub-tables as a message lists them.
/// A network material's key for its kinematics: `kinematics = "finite"`
/// (absent) or `"small"` ([`Strain`]).
const KINEMATICS: &str = "kinematics";

fn part_list() -> String {
    let mut names = vec!["[equilibrium]".to_string()];
    names.extend(PARTS.iter().map(|k| {
        if k.max_count == 1 {
            format!("[{}]", k.table)
        } else {
            format!("[[{}]]", k.table)
        }
    }));
    names.join(", ")
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
