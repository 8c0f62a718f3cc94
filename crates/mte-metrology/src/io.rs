//! Text inputs: CSV tables for the tracker network (format in `docs/formats.md`) and a small
//! reader for GNU Gama `gama-local` XML input files (3-D points and `s-distance` observations).
//! Every error names the source, the line and the field.

use crate::error::{MetrologyError, Result};
use crate::network::{
    DeadPath, LengthObservation, LengthUncertainty, Network, Station, Target, Vec3,
};
use mte_linalg::csv::CsvTable;
use std::collections::HashMap;

fn perr(src: &str, line: usize, what: impl Into<String>) -> MetrologyError {
    MetrologyError::Parse {
        source_name: src.to_string(),
        line,
        what: what.into(),
    }
}

/// Largest |coordinate| of a station or target the reader accepts, mm (exclusive): 1 km.
pub const MAX_COORDINATE_MM: f64 = 1e6;
/// Largest measured length the reader accepts, mm (exclusive): 1 km.
pub const MAX_LENGTH_MM: f64 = 1e6;
/// Largest |dead path| the reader accepts, mm (exclusive): 100 m.
pub const MAX_DEAD_PATH_MM: f64 = 1e5;
/// Range of a length's standard uncertainty the reader accepts, µm: from 1 nm (no
/// interferometer resolves less) to 10 mm (exclusive).
pub const SIGMA_RANGE_UM: (f64, f64) = (1e-3, 1e4);

const COORD_MEANING: &str =
    "a station or target 1 km or more from the origin is not a machine-tool measurement (mm)";

/// Every id of a table once: a second occurrence names both lines.
fn unique_ids(c: &CsvTable, col: usize, kind: &str) -> Result<()> {
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for (line, f) in &c.rows {
        if let Some(first) = seen.insert(f[col].as_str(), *line) {
            return Err(perr(
                &c.source_name,
                *line,
                format!(
                    "field `id`: duplicate {kind} id `{}`, first on line {first}",
                    f[col]
                ),
            ));
        }
    }
    Ok(())
}

/// The three CSV texts of a network, as [`network_from_csv`] reads them: stations (with their
/// dead path and whether it is free), nominal targets, lengths with their σ.
///
/// ```
/// use mte_metrology::io::{network_from_csv, network_to_csv};
/// use mte_metrology::network::LengthUncertainty;
/// let net = network_from_csv(
///     ("s", "id,x_mm,y_mm,z_mm\nS1,0,0,0\n"),
///     ("t", "id,x_mm,y_mm,z_mm\nP1,100,0,0\n"),
///     ("l", "station,target,length_mm,sigma_um\nS1,P1,100.0,1.5\n"),
///     LengthUncertainty::SEED004,
/// )
/// .unwrap();
/// let (s, t, l) = network_to_csv(&net);
/// let again = network_from_csv(("s", &s), ("t", &t), ("l", &l), LengthUncertainty::SEED004).unwrap();
/// assert_eq!(again, net);
/// ```
pub fn network_to_csv(network: &Network) -> (String, String, String) {
    use std::fmt::Write;
    let mut s = String::from("id,x_mm,y_mm,z_mm,dead_path_mm,dead_path\n");
    for st in &network.stations {
        let p = st.position_mm;
        let kind = match st.dead_path {
            DeadPath::Free => "free",
            DeadPath::Fixed => "fixed",
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{kind}",
            st.id, p.x, p.y, p.z, st.dead_path_mm
        );
    }
    let mut t = String::from("id,x_mm,y_mm,z_mm\n");
    for tg in &network.targets {
        let p = tg.nominal_mm;
        let _ = writeln!(t, "{},{},{},{}", tg.id, p.x, p.y, p.z);
    }
    let mut l = String::from("station,target,length_mm,sigma_um\n");
    for o in &network.observations {
        let _ = writeln!(
            l,
            "{},{},{:.9},{:.6}",
            network.stations[o.station].id,
            network.targets[o.target].id,
            o.length_mm,
            o.sigma_mm * 1e3
        );
    }
    (s, t, l)
}

/// Build a network from three CSV texts:
/// * stations: `id,x_mm,y_mm,z_mm[,dead_path_mm][,dead_path]` (`dead_path` = `free` | `fixed`, default `free`);
/// * targets: `id,x_mm,y_mm,z_mm` (nominal, commanded positions);
/// * lengths: `station,target,length_mm[,sigma_um]` (without `sigma_um`, σ from `default_u`).
///
/// # Errors
/// Parse errors naming file, line and field; unknown station/target ids.
///
/// ```
/// let st = "id,x_mm,y_mm,z_mm\nS1,0,0,0\n";
/// let tg = "id,x_mm,y_mm,z_mm\nP1,100,0,0\n";
/// let ln = "station,target,length_mm\nS1,P1,100.0\n";
/// let net = mte_metrology::io::network_from_csv(("s", st), ("t", tg), ("l", ln),
///     mte_metrology::network::LengthUncertainty::SEED004).unwrap();
/// assert_eq!(net.observations[0].length_mm, 100.0);
/// ```
pub fn network_from_csv(
    stations: (&str, &str),
    targets: (&str, &str),
    lengths: (&str, &str),
    default_u: LengthUncertainty,
) -> Result<Network> {
    let sc = CsvTable::parse(stations.1, stations.0)?;
    let (ci, cx, cy, cz) = (
        sc.require("id")?,
        sc.require("x_mm")?,
        sc.require("y_mm")?,
        sc.require("z_mm")?,
    );
    let cd = sc.column("dead_path_mm");
    let cf = sc.column("dead_path");
    unique_ids(&sc, ci, "station")?;
    let mut st = Vec::new();
    for (i, r) in sc.rows.iter().enumerate() {
        let dp = match cf.map(|c| r.1[c].to_ascii_lowercase()) {
            None => DeadPath::Free,
            Some(s) if s == "free" || s.is_empty() => DeadPath::Free,
            Some(s) if s == "fixed" => DeadPath::Fixed,
            Some(s) => {
                return Err(perr(
                    &sc.source_name,
                    r.0,
                    format!("field `dead_path`: expected `free` or `fixed`, got `{s}`"),
                ));
            }
        };
        st.push(Station {
            id: r.1[ci].clone(),
            position_mm: Vec3::new(
                sc.number_within(i, cx, MAX_COORDINATE_MM, COORD_MEANING)?,
                sc.number_within(i, cy, MAX_COORDINATE_MM, COORD_MEANING)?,
                sc.number_within(i, cz, MAX_COORDINATE_MM, COORD_MEANING)?,
            ),
            dead_path_mm: match cd {
                Some(c) => sc.number_within(
                    i,
                    c,
                    MAX_DEAD_PATH_MM,
                    "a dead path of 100 m or more is not a tracker's (mm)",
                )?,
                None => 0.0,
            },
            dead_path: dp,
        });
    }
    let tc = CsvTable::parse(targets.1, targets.0)?;
    let (ti, tx, ty, tz) = (
        tc.require("id")?,
        tc.require("x_mm")?,
        tc.require("y_mm")?,
        tc.require("z_mm")?,
    );
    unique_ids(&tc, ti, "target")?;
    let mut tg = Vec::new();
    for (i, r) in tc.rows.iter().enumerate() {
        tg.push(Target {
            id: r.1[ti].clone(),
            nominal_mm: Vec3::new(
                tc.number_within(i, tx, MAX_COORDINATE_MM, COORD_MEANING)?,
                tc.number_within(i, ty, MAX_COORDINATE_MM, COORD_MEANING)?,
                tc.number_within(i, tz, MAX_COORDINATE_MM, COORD_MEANING)?,
            ),
        });
    }
    let smap: HashMap<&str, usize> = st
        .iter()
        .enumerate()
        .map(|(i, s)| (s.id.as_str(), i))
        .collect();
    let tmap: HashMap<&str, usize> = tg
        .iter()
        .enumerate()
        .map(|(i, s)| (s.id.as_str(), i))
        .collect();
    let lc = CsvTable::parse(lengths.1, lengths.0)?;
    let (ls, lt, ll) = (
        lc.require("station")?,
        lc.require("target")?,
        lc.require("length_mm")?,
    );
    let lsig = lc.column("sigma_um");
    let mut obs = Vec::new();
    for (i, r) in lc.rows.iter().enumerate() {
        let s = *smap.get(r.1[ls].as_str()).ok_or_else(|| {
            perr(
                &lc.source_name,
                r.0,
                format!("field `station`: unknown station id `{}`", r.1[ls]),
            )
        })?;
        let t = *tmap.get(r.1[lt].as_str()).ok_or_else(|| {
            perr(
                &lc.source_name,
                r.0,
                format!("field `target`: unknown target id `{}`", r.1[lt]),
            )
        })?;
        let l = lc.number_within(
            i,
            ll,
            MAX_LENGTH_MM,
            "a length of 1 km or more is not a tracker measurement (mm)",
        )?;
        if l < 0.0 {
            return Err(perr(
                &lc.source_name,
                r.0,
                format!("field `length_mm`: negative length {l}"),
            ));
        }
        let sigma_mm = match lsig {
            Some(c) => {
                let v = lc.number(i, c)?;
                if !(SIGMA_RANGE_UM.0..SIGMA_RANGE_UM.1).contains(&v) {
                    return Err(perr(
                        &lc.source_name,
                        r.0,
                        format!(
                            "column `sigma_um`: `{}` is out of range [{:e}, {:e}) µm: no length is measured better than 1 nm or worse than 10 mm",
                            r.1[c], SIGMA_RANGE_UM.0, SIGMA_RANGE_UM.1
                        ),
                    ));
                }
                v * 1e-3
            }
            None => default_u.sigma_mm(l),
        };
        obs.push(LengthObservation {
            station: s,
            target: t,
            length_mm: l,
            sigma_mm,
        });
    }
    Ok(Network {
        stations: st,
        targets: tg,
        observations: obs,
    })
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

/// Read a GNU Gama `gama-local` input (the simple structure of
/// `fixtures/metrology-xcheck/mlat-free-4x24.gkf`): `<point id x y z adj>` in metres
/// (`adj="XYZ"` = constrained target, `adj="xyz"` = free station), `<obs from>` with
/// `<s-distance to val stdev>` (val in m, stdev in mm). Coordinates become mm, dead paths are
/// fixed at 0 (Gama has no additive constant).
///
/// # Errors
/// A missing attribute or unknown point, naming the line.
pub fn network_from_gama(source_name: &str, text: &str) -> Result<Network> {
    let mut stations = Vec::new();
    let mut targets = Vec::new();
    let mut raw_obs: Vec<(usize, String, String, f64, f64)> = Vec::new();
    let mut from: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        let num = |name: &str| -> Result<f64> {
            let v = attr(l, name)
                .ok_or_else(|| perr(source_name, i + 1, format!("missing attribute `{name}`")))?;
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    perr(
                        source_name,
                        i + 1,
                        format!("attribute `{name}`: expected a number, got `{v}`"),
                    )
                })
        };
        if l.starts_with("<point ") {
            let id = attr(l, "id").ok_or_else(|| perr(source_name, i + 1, "point without `id`"))?;
            let p = Vec3::new(num("x")?, num("y")?, num("z")?) * 1000.0;
            match attr(l, "adj").as_deref() {
                Some("XYZ") => targets.push(Target { id, nominal_mm: p }),
                Some("xyz") => stations.push(Station {
                    id,
                    position_mm: p,
                    dead_path_mm: 0.0,
                    dead_path: DeadPath::Fixed,
                }),
                other => {
                    return Err(perr(
                        source_name,
                        i + 1,
                        format!(
                            "point `{id}`: adj must be `XYZ` (target) or `xyz` (station), got {other:?}"
                        ),
                    ));
                }
            }
        } else if l.starts_with("<obs ") {
            from = Some(
                attr(l, "from").ok_or_else(|| perr(source_name, i + 1, "<obs> without `from`"))?,
            );
        } else if l.starts_with("<s-distance ") {
            let f = from
                .clone()
                .ok_or_else(|| perr(source_name, i + 1, "s-distance outside <obs from=...>"))?;
            let to =
                attr(l, "to").ok_or_else(|| perr(source_name, i + 1, "s-distance without `to`"))?;
            raw_obs.push((i + 1, f, to, num("val")? * 1000.0, num("stdev")?));
        }
    }
    let mut obs = Vec::new();
    for (line, f, t, v, s) in raw_obs {
        let (si, ti) = match (
            stations.iter().position(|x| x.id == f),
            targets.iter().position(|x| x.id == t),
        ) {
            (Some(a), Some(b)) => (a, b),
            _ => {
                return Err(perr(
                    source_name,
                    line,
                    format!("s-distance {f} → {t}: `from` must be a station, `to` a target"),
                ));
            }
        };
        obs.push(LengthObservation {
            station: si,
            target: ti,
            length_mm: v,
            sigma_mm: s,
        });
    }
    Ok(Network {
        stations,
        targets,
        observations: obs,
    })
}
