//! The states of an ensemble's members, stored flat: one row of `n` numbers
//! per member. Ten thousand members are one allocation, not ten thousand.

/// One row of `n` state components per member.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct States {
    pub n: usize,
    pub data: Vec<f64>,
}

impl States {
    /// The rows, copied into one buffer (all of one length).
    pub fn from_rows(rows: &[Vec<f64>]) -> States {
        let n = rows.first().map_or(0, Vec::len);
        let mut data = Vec::with_capacity(rows.len() * n);
        for row in rows {
            data.extend_from_slice(row);
        }
        States { n, data }
    }

    /// The number of members.
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.n).unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Member `k`'s state.
    pub fn row(&self, k: usize) -> &[f64] {
        &self.data[k * self.n..(k + 1) * self.n]
    }

    /// Every member's state, in order.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        self.data.chunks(self.n.max(1))
    }
}
