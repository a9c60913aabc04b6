//! The uniform grid of points that answers the measure's radius queries.

use crate::Vec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A small multiplicative hasher for integer cell keys (the default SipHash
/// dominated the neighbour queries); not for untrusted keys, which these
/// are not.
#[derive(Default)]
pub(super) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

pub(super) type Cell = (i64, i64, i64);
type CellMap = HashMap<Cell, Vec<u32>, BuildHasherDefault<CellHasher>>;

/// A uniform grid of points for radius queries.
pub(super) struct Grid {
    size: f64,
    cells: CellMap,
}

impl Grid {
    pub(super) fn cell(size: f64, x: Vec3) -> Cell {
        let c = (x / size).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    }
    pub(super) fn new(size: f64, points: impl Iterator<Item = (u32, Vec3)>) -> Self {
        let mut cells: CellMap = HashMap::default();
        for (i, p) in points {
            cells.entry(Self::cell(size, p)).or_default().push(i);
        }
        Grid { size, cells }
    }
    /// Calls `f` with every stored index in the 27 cells around `x`
    /// (a superset of the points within `size` of `x`).
    pub(super) fn around(&self, x: Vec3, mut f: impl FnMut(u32)) {
        let (i, j, k) = Self::cell(self.size, x);
        for di in -1..=1 {
            for dj in -1..=1 {
                for dk in -1..=1 {
                    let c = (
                        i.saturating_add(di),
                        j.saturating_add(dj),
                        k.saturating_add(dk),
                    );
                    if let Some(v) = self.cells.get(&c) {
                        for &p in v {
                            f(p);
                        }
                    }
                }
            }
        }
    }
}
