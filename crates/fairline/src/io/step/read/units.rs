//! The file's length unit and distance uncertainty (ISO 10303-41 units).

use std::collections::HashSet;

use crate::io::step::p21::{Exchange, Instance, Value};
use crate::io::units::LengthUnit;

/// The file's distance uncertainty (the first positive
/// `UNCERTAINTY_MEASURE_WITH_UNIT` value, in the file's length unit), 0
/// when it states none.
pub(super) fn distance_uncertainty(ex: &Exchange) -> f64 {
    let mut ids: Vec<u64> = ex.order.clone();
    ids.sort_unstable();
    ids.iter()
        .filter_map(|id| ex.instances[id].part("UNCERTAINTY_MEASURE_WITH_UNIT"))
        .filter_map(|p| p.first().and_then(Value::number))
        .find(|x| x.is_finite() && *x > 0.0)
        .unwrap_or(0.0)
}

pub(super) fn collect_refs(v: &[Value], out: &mut HashSet<u64>) {
    for x in v {
        match x {
            Value::Ref(id) => {
                out.insert(*id);
            }
            Value::List(l) => collect_refs(l, out),
            Value::Typed(_, b) => collect_refs(std::slice::from_ref(b), out),
            _ => {}
        }
    }
}

/// The file's length unit and radians per plane-angle unit (1 when
/// absent): the units a GLOBAL_UNIT_ASSIGNED_CONTEXT assigns, else the first
/// LENGTH_UNIT / PLANE_ANGLE_UNIT instances.
pub(super) fn units(ex: &Exchange) -> (Option<LengthUnit>, f64) {
    let mut ids: Vec<u64> = ex.order.clone();
    ids.sort_unstable();
    let mut candidates: Vec<&Instance> = Vec::new();
    for id in &ids {
        if let Some(Value::List(l)) = ex.instances[id]
            .part("GLOBAL_UNIT_ASSIGNED_CONTEXT")
            .and_then(|p| p.first())
        {
            for v in l {
                if let Value::Ref(u) = v
                    && let Some(i) = ex.instances.get(u)
                {
                    candidates.push(i);
                }
            }
        }
    }
    candidates.extend(ids.iter().map(|id| &ex.instances[id]));
    let mut length = None;
    let mut angle = None;
    for i in candidates {
        if length.is_none() && i.is("LENGTH_UNIT") {
            length = unit_size(ex, i, 0).map(|m| {
                let named = LengthUnit::from_iges_name(&unit_name(i))
                    .filter(|u| (u.metres - m).abs() <= 1e-9 * m);
                named.unwrap_or(LengthUnit {
                    name: unit_name(i),
                    metres: m,
                })
            });
        }
        if angle.is_none() && i.is("PLANE_ANGLE_UNIT") {
            angle = unit_size(ex, i, 0);
        }
    }
    (length, angle.filter(|a| *a > 0.0).unwrap_or(1.0))
}

/// Metres (or radians) per unit of an SI_UNIT or CONVERSION_BASED_UNIT.
fn unit_size(ex: &Exchange, i: &Instance, depth: usize) -> Option<f64> {
    if depth > 8 {
        return None;
    }
    if let Some(si) = i.part("SI_UNIT") {
        let prefix = match si.first() {
            Some(Value::Enum(p)) => match p.as_str() {
                "MILLI" => 1e-3,
                "CENTI" => 1e-2,
                "DECI" => 1e-1,
                "KILO" => 1e3,
                "MICRO" => 1e-6,
                "NANO" => 1e-9,
                _ => return None,
            },
            _ => 1.0,
        };
        return Some(prefix);
    }
    if let Some(cb) = i.part("CONVERSION_BASED_UNIT") {
        let Some(Value::Ref(m)) = cb.get(1) else {
            return None;
        };
        let m = ex.instances.get(m)?;
        let (_, p) = m
            .parts
            .iter()
            .find(|(n, _)| n.contains("MEASURE_WITH_UNIT"))?;
        let factor = p.first()?.number()?;
        let Some(Value::Ref(u)) = p.get(1) else {
            return None;
        };
        let base = unit_size(ex, ex.instances.get(u)?, depth + 1)?;
        return Some(factor * base).filter(|x| x.is_finite() && *x > 0.0);
    }
    None
}

fn unit_name(i: &Instance) -> String {
    if let Some(cb) = i.part("CONVERSION_BASED_UNIT")
        && let Some(Value::Text(t)) = cb.first()
    {
        return t.to_ascii_uppercase();
    }
    match i.part("SI_UNIT") {
        Some([Value::Enum(p), Value::Enum(_)]) if p == "MILLI" => "MM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "CENTI" => "CM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "KILO" => "KM".into(),
        Some([Value::Enum(p), Value::Enum(_)]) if p == "MICRO" => "UM".into(),
        _ => "M".into(),
    }
}
