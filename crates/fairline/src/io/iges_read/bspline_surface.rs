//! Rational B-spline surfaces (entity 128, IGES 5.3 §4.24).

use super::params::{INT, REAL, line_of, param};
use super::records::Iges;
use super::{IgesError, IgesSurface};
use crate::Vec3;
use crate::bspline::BSplineSurface;

/// Entity 128, rational B-spline surface (IGES 5.3 §4.24).
pub(super) fn read_entity_128(
    g: &Iges<'_>,
    k: usize,
    trimmed: bool,
) -> Result<IgesSurface, IgesError> {
    let e = &g.dir[k];
    let p = g.parameters(k)?;
    let line = p.first().map_or(e.line, |t| t.1);
    let nonneg = |n: usize| -> Result<usize, IgesError> {
        let v = param(g, k, &p, n, line, &INT)?;
        usize::try_from(v).map_err(|_| {
            g.entity_error(
                k,
                line_of(&p, n, line),
                format!("parameter {n} is negative ({v})"),
            )
        })
    };
    let (k1, k2, m1, m2) = (nonneg(1)?, nonneg(2)?, nonneg(3)?, nonneg(4)?);
    let mut prop = [0i64; 5];
    for (n, v) in prop.iter_mut().enumerate() {
        *v = param(g, k, &p, 5 + n, line, &INT)?;
    }
    let (count_u, count_v) = (k1 + 1, k2 + 1);
    let (nk_u, nk_v) = (count_u + m1 + 1, count_v + m2 + 1);
    let c = count_u.saturating_mul(count_v);
    let needed = 10usize
        .saturating_add(nk_u)
        .saturating_add(nk_v)
        .saturating_add(c.saturating_mul(4))
        .saturating_add(4);
    if p.len() < needed {
        return Err(g.entity_error(
            k,
            line_of(&p, p.len(), line),
            format!(
                "{} parameters, but K1={k1}, K2={k2}, M1={m1}, M2={m2} need {needed}",
                p.len()
            ),
        ));
    }
    let reals = |from: usize, n: usize| -> Result<Vec<f64>, IgesError> {
        (from..from + n)
            .map(|i| param(g, k, &p, i, line, &REAL))
            .collect()
    };
    let mut at = 10;
    let knots_u = reals(at, nk_u)?;
    at += nk_u;
    let knots_v = reals(at, nk_v)?;
    at += nk_v;
    let w_file = reals(at, c)?;
    at += c;
    let xyz = reals(at, 3 * c)?;
    at += 3 * c;
    let range = reals(at, 4)?;
    let transform = if e.transform != 0 {
        let t = g.entry(e.transform).ok_or_else(|| {
            g.entity_error(
                k,
                e.line,
                format!(
                    "transformation pointer {} is not a directory entry",
                    e.transform
                ),
            )
        })?;
        Some(g.transform(t, 0)?)
    } else {
        None
    };
    // IGES orders control points and weights with the u index fastest.
    let mut points = vec![Vec3::ZERO; c];
    let mut weights = vec![0.0; c];
    for j in 0..count_v {
        for i in 0..count_u {
            let f = j * count_u + i;
            let mut q = Vec3::new(xyz[3 * f], xyz[3 * f + 1], xyz[3 * f + 2]);
            if let Some(t) = &transform {
                q = t.transform_point3(q);
            }
            points[i * count_v + j] = q;
            weights[i * count_v + j] = w_file[f];
        }
    }
    let rational = prop[2] == 0;
    let surface = BSplineSurface::from_flat(
        m1,
        m2,
        knots_u,
        knots_v,
        [count_u, count_v],
        points,
        rational.then_some(weights),
    )
    .map_err(|source| IgesError::Surface {
        entity: 2 * k + 1,
        line,
        source,
    })?;
    Ok(IgesSurface {
        surface,
        directory_entry: 2 * k + 1,
        entity_type: 128,
        form: e.form,
        rational,
        closed: [prop[0] == 1, prop[1] == 1],
        periodic: [prop[3] == 1, prop[4] == 1],
        parameter_range: [range[0], range[1], range[2], range[3]],
        transformed: transform.is_some(),
        trimmed,
        trim_entity: None,
    })
}
