//! Units of error values and axis positions. Inside the crate: mm and rad.

use crate::error::{Error, Result};

/// Physical kind of a quantity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A length (internal unit mm).
    Length,
    /// An angle (internal unit rad).
    Angle,
}

impl Kind {
    /// Internal unit name (`mm` or `rad`).
    pub fn internal_unit(self) -> &'static str {
        match self {
            Kind::Length => "mm",
            Kind::Angle => "rad",
        }
    }
    /// Unit reports use (`um` or `urad`).
    pub fn report_unit(self) -> Unit {
        match self {
            Kind::Length => Unit::Um,
            Kind::Angle => Unit::Urad,
        }
    }
}

/// A unit accepted in files: as a key suffix (`value_um`) or in a `unit` field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Unit {
    /// millimetre
    Mm,
    /// micrometre
    Um,
    /// nanometre
    Nm,
    /// radian
    Rad,
    /// milliradian
    Mrad,
    /// microradian (also µm/m)
    Urad,
    /// arc second
    Arcsec,
    /// degree
    Deg,
}

/// All units, for suffix matching.
pub const ALL_UNITS: [Unit; 8] = [
    Unit::Mm,
    Unit::Um,
    Unit::Nm,
    Unit::Rad,
    Unit::Mrad,
    Unit::Urad,
    Unit::Arcsec,
    Unit::Deg,
];

impl Unit {
    /// Parse a unit name: `mm`, `um` (`µm`), `nm`, `rad`, `mrad`, `urad` (`µrad`, `um/m`), `arcsec`, `deg`.
    ///
    /// # Errors
    /// [`Error::Unit`] for anything else.
    pub fn parse(s: &str, field: &str) -> Result<Unit> {
        let t = s.trim();
        let u = match t {
            "mm" => Unit::Mm,
            "um" | "µm" | "μm" => Unit::Um,
            "nm" => Unit::Nm,
            "rad" => Unit::Rad,
            "mrad" => Unit::Mrad,
            "urad" | "µrad" | "μrad" | "um/m" | "µm/m" => Unit::Urad,
            "arcsec" | "″" => Unit::Arcsec,
            "deg" | "°" => Unit::Deg,
            _ => {
                return Err(Error::Unit {
                    field: field.to_string(),
                    unit: s.to_string(),
                    message: "expected one of mm, um, nm, rad, mrad, urad, arcsec, deg".into(),
                });
            }
        };
        Ok(u)
    }
    /// The suffix used in keys and column names (`um`, `urad`, ...).
    pub fn suffix(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Um => "um",
            Unit::Nm => "nm",
            Unit::Rad => "rad",
            Unit::Mrad => "mrad",
            Unit::Urad => "urad",
            Unit::Arcsec => "arcsec",
            Unit::Deg => "deg",
        }
    }
    /// Length or angle.
    pub fn kind(self) -> Kind {
        match self {
            Unit::Mm | Unit::Um | Unit::Nm => Kind::Length,
            _ => Kind::Angle,
        }
    }
    /// Factor from this unit to the internal unit (mm or rad): `internal = value · factor`.
    pub fn to_internal(self) -> f64 {
        match self {
            Unit::Mm => 1.0,
            Unit::Um => 1e-3,
            Unit::Nm => 1e-6,
            Unit::Rad => 1.0,
            Unit::Mrad => 1e-3,
            Unit::Urad => 1e-6,
            Unit::Arcsec => std::f64::consts::PI / 648_000.0,
            Unit::Deg => std::f64::consts::PI / 180.0,
        }
    }
    /// Check that this unit measures `kind`.
    ///
    /// # Errors
    /// [`Error::Unit`] naming `field` when the kinds differ (unit mismatch).
    pub fn expect_kind(self, kind: Kind, field: &str) -> Result<()> {
        if self.kind() == kind {
            Ok(())
        } else {
            Err(Error::Unit {
                field: field.to_string(),
                unit: self.suffix().to_string(),
                message: format!(
                    "this is a unit of {:?}, but {field} is a {:?} (use {})",
                    self.kind(),
                    kind,
                    match kind {
                        Kind::Length => "mm, um or nm",
                        Kind::Angle => "rad, mrad, urad, arcsec or deg",
                    }
                ),
            })
        }
    }
}

/// Split `base_unit` (e.g. `value_um`) into (`value`, unit) when the suffix is a known unit.
pub fn split_suffix(key: &str) -> Option<(&str, Unit)> {
    let (base, suf) = key.rsplit_once('_')?;
    let u = ALL_UNITS.into_iter().find(|u| u.suffix() == suf)?;
    Some((base, u))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn conversions() {
        // 1 arcsec = π/648000 rad = 4.8481368 µrad (definition of the arc second).
        assert_relative_eq!(
            Unit::Arcsec.to_internal() / Unit::Urad.to_internal(),
            4.848_136_811,
            epsilon = 1e-9
        );
        assert_eq!(split_suffix("value_um"), Some(("value", Unit::Um)));
        assert_eq!(split_suffix("range_deg"), Some(("range", Unit::Deg)));
        assert_eq!(split_suffix("value"), None);
        assert!(Unit::Um.expect_kind(Kind::Angle, "EBX").is_err());
        assert!(Unit::parse("inch", "f").is_err());
    }
}
