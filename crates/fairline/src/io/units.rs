//! Length units of CAD files (IGES Global section fields 14–15, STEP
//! `LENGTH_UNIT` / `SI_UNIT` / `CONVERSION_BASED_UNIT`).
//!
//! fairline keeps coordinates in the unit of the file they came from (no
//! rescaling on import), remembers that unit, and writes it back, so that a
//! read → write round trip keeps every coordinate bit-identical.

/// A length unit: its name as CAD files spell it and its size in metres.
#[derive(Clone, Debug, PartialEq)]
pub struct LengthUnit {
    /// Upper-case name (`MM`, `M`, `IN`, …).
    pub name: String,
    /// Metres per unit (0.001 for millimetres).
    pub metres: f64,
}

/// The units with an IGES unit flag (IGES 5.3 §2.2.4.3, Global field 14):
/// `(flag, name, metres per unit)`.
const IGES_UNITS: &[(i64, &str, f64)] = &[
    (1, "IN", 0.0254),
    (2, "MM", 0.001),
    (4, "FT", 0.3048),
    (5, "MI", 1609.344),
    (6, "M", 1.0),
    (7, "KM", 1000.0),
    (8, "MIL", 0.0000254),
    (9, "UM", 0.000001),
    (10, "CM", 0.01),
    (11, "UIN", 0.0000000254),
];

impl LengthUnit {
    /// Millimetres, the default of CAD exchange files.
    pub fn millimetre() -> Self {
        Self::named("MM", 0.001)
    }

    /// Metres.
    pub fn metre() -> Self {
        Self::named("M", 1.0)
    }

    /// Inches.
    pub fn inch() -> Self {
        Self::named("IN", 0.0254)
    }

    fn named(name: &str, metres: f64) -> Self {
        Self {
            name: name.into(),
            metres,
        }
    }

    /// The unit of an IGES unit name (Global field 15: `MM`, `IN`, `INCH`,
    /// `M`, …), `None` when the name is not one IGES defines.
    pub fn from_iges_name(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_uppercase();
        let n = match n.as_str() {
            "INCH" | "INCHES" => "IN",
            "MILLIMETRE" | "MILLIMETER" => "MM",
            "METRE" | "METER" => "M",
            "FOOT" | "FEET" => "FT",
            other => other,
        };
        IGES_UNITS
            .iter()
            .find(|(_, u, _)| *u == n)
            .map(|&(_, u, m)| Self::named(u, m))
    }

    /// The IGES unit flag (Global field 14) of this unit: a defined flag when
    /// the size matches one (to 1e-9 relative), otherwise 3 ("named in
    /// field 15").
    pub fn iges_flag(&self) -> i64 {
        IGES_UNITS
            .iter()
            .find(|(_, _, m)| (m - self.metres).abs() <= 1e-9 * m)
            .map_or(3, |&(f, _, _)| f)
    }

    /// The IGES name of this unit (`MM`, `IN`, …; the own name for others).
    pub fn iges_name(&self) -> String {
        IGES_UNITS
            .iter()
            .find(|(_, _, m)| (m - self.metres).abs() <= 1e-9 * m)
            .map_or_else(|| self.name.clone(), |&(_, u, _)| u.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_iges_names_and_flags() {
        assert_eq!(
            LengthUnit::from_iges_name("mm"),
            Some(LengthUnit::millimetre())
        );
        assert_eq!(LengthUnit::from_iges_name("INCH"), Some(LengthUnit::inch()));
        assert_eq!(LengthUnit::from_iges_name("parsec"), None);
        assert_eq!(LengthUnit::millimetre().iges_flag(), 2);
        assert_eq!(LengthUnit::inch().iges_flag(), 1);
        assert_eq!(LengthUnit::metre().iges_flag(), 6);
        let odd = LengthUnit {
            name: "FURLONG".into(),
            metres: 201.168,
        };
        assert_eq!(odd.iges_flag(), 3);
        assert_eq!(odd.iges_name(), "FURLONG");
    }
}
