//! A face a reader could not read, as every surface reader reports it.

/// A face of a file that was not read: what it is, where, and why.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Unreadable {
    /// The entity: IGES `entity 144 (DE 35, line 77)`, STEP `#120
    /// ADVANCED_FACE`.
    pub entity: String,
    /// Why it could not be read.
    pub reason: String,
    /// The area of the face where it can be estimated (the untrimmed area
    /// of a base surface that was read: an upper bound), in the file's
    /// unit squared.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimated_area: Option<f64>,
}

impl std::fmt::Display for Unreadable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.entity, self.reason)
    }
}
