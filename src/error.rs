//! Error types: one small `Copy` enum per layer, each with `Display`, `core::error::Error` and,
//! under the `defmt` feature, `defmt::Format`.
//!
//! Running out of time is not an error (the planner reports it as progress); these enums are for
//! input the planner cannot accept and for capacities that are exhausted. A function that
//! returns one of them has left its data structure exactly as it was.

macro_rules! error_enum {
    ($(#[$meta:meta])* pub enum $name:ident { $($(#[$vmeta:meta])* $variant:ident => $text:literal,)+ }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum $name {
            $($(#[$vmeta])* $variant,)+
        }

        impl core::fmt::Display for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str(match self {
                    $(Self::$variant => $text,)+
                })
            }
        }

        impl core::error::Error for $name {}
    };
}

error_enum! {
    /// A grid description that cannot be used.
    pub enum MapError {
        /// Width or height is zero.
        EmptyGrid => "grid width and height must be positive",
        /// The byte slice holds fewer than `ceil(width * height / 8)` bytes.
        BufferTooShort => "occupancy buffer shorter than width * height bits",
        /// The cell size is not a finite positive number, or its inverse or the map's extent
        /// is not finite.
        BadCellSize => "cell size must be finite and positive, with a finite inverse and extent",
        /// A live cell edit on a map that has no overlay (`Map::with_overlay`).
        NoOverlay => "the map has no live overlay to edit",
        /// A live cell edit names a cell outside the grid.
        CellOutside => "cell outside the grid",
        /// The robot's radius is NaN, infinite or negative.
        BadRadius => "robot radius must be finite and not negative",
        /// The robot's disc fits nowhere: every cell lies within its radius of an obstacle or
        /// of the map's edge.
        NoRoom => "no cell of the map has room for the robot's radius",
        /// A baked configuration space (`Map::with_baked_body`) has another size or cell size
        /// than the grid.
        BodyMismatch => "the inflated grid's size or cell size differs from the map's grid",
        /// Live cells on a map whose inflated grid is read-only (baked into flash): a body
        /// with live cells needs the inflated grid in a buffer (`Map::with_body`).
        BodyInFlash => "live cells with a robot body need the inflated grid in a RAM buffer (Map::with_body)",
        /// A clearance margin (`clearance::clearance_field`) is NaN, infinite, negative or
        /// wider than 255 cells.
        BadMargin => "clearance margin must be finite, not negative and at most 255 cells",
        /// A clearance field (`Map::with_clearance`) holds fewer bytes than the grid has
        /// cells.
        FieldTooShort => "clearance field shorter than width * height bytes",
    }
}

error_enum! {
    /// A position given at the API edge that the planner refuses.
    pub enum InputError {
        /// A coordinate is NaN or infinite.
        NotFinite => "coordinate is NaN or infinite",
        /// The position lies outside the map's bounds.
        OutOfBounds => "position outside the map",
        /// The position lies in (or within the safety margin of) an obstacle.
        InObstacle => "position inside an obstacle",
        /// The position is free for a point but closer to a wall (or the map's edge) than the
        /// robot's radius: the robot's disc does not fit there.
        NoRoom => "position closer to a wall than the robot's radius",
        /// The assisting metric places the position at an infinite distance (cut off from the
        /// start's free region).
        Unreachable => "position unreachable from the start",
    }
}

/// The rule a configuration value keeps (each value's rule is in the parameter table,
/// [`crate::config::PARAMS`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rule {
    /// Any value of its type.
    Any,
    /// A number: finite and above zero.
    Positive,
    /// A number: finite and not below zero.
    NonNegative,
    /// A count: 1 or more.
    AtLeastOne,
    /// A probability: in `[0, 1]` (not NaN).
    Unit,
    /// A duration: longer than zero.
    NonZero,
}

impl Rule {
    /// The rule in words, as error messages and the configuration reference give it.
    pub const fn text(self) -> &'static str {
        match self {
            Self::Any => "any value",
            Self::Positive => "finite and positive",
            Self::NonNegative => "finite and not negative",
            Self::AtLeastOne => "at least 1",
            Self::Unit => "in [0, 1]",
            Self::NonZero => "longer than zero",
        }
    }
}

/// A [`crate::Config`] value out of range: its name in the parameter table
/// ([`crate::config::PARAMS`]) and the rule it breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigError {
    /// The value's name (`"e_max"`, `"p_goal"`, ...).
    pub param: &'static str,
    /// The rule it breaks.
    pub rule: Rule,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{} must be {}", self.param, self.rule.text())
    }
}

impl core::error::Error for ConfigError {}

/// Why a planner could not be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetupError {
    /// A configuration field is out of range.
    Config(ConfigError),
    /// The start position is refused.
    Start(InputError),
    /// The map's scale is out of range: squared distances across it overflow `f32` (maps over
    /// about 1e19 m), or vanish at the duplicate scale (cells under about 1e-15 m), or the
    /// spatial index cannot cover it.
    Map,
    /// The metric was not made for this map: a diffusion table baked from another grid
    /// (`DiffusionTable::check_map`).
    Metric(TableError),
    /// The configuration's `robot_radius` is larger than the radius the map's grid was
    /// inflated for (`Map::with_body`, `Map::with_baked_body`; 0 without a body).
    Body,
    /// The configuration's `clearance_weight` is above 0 but the map has no clearance field
    /// (`Map::with_clearance`), or the crate was built without its `clearance` feature: the
    /// preference would silently do nothing.
    Clearance,
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Config(e) => write!(f, "bad configuration: {e}"),
            Self::Start(e) => write!(f, "bad start: {e}"),
            Self::Metric(e) => write!(f, "metric does not fit the map: {e}"),
            Self::Body => f.write_str(
                "robot_radius exceeds the radius the map was inflated for (Map::with_body)",
            ),
            Self::Clearance => f.write_str(
                "clearance_weight is set but the map has no clearance field (Map::with_clearance) or the crate lacks its `clearance` feature",
            ),
            Self::Map => {
                f.write_str("map scale out of range: squared distances overflow or vanish in f32")
            }
        }
    }
}

impl core::error::Error for SetupError {}

impl From<ConfigError> for SetupError {
    fn from(e: ConfigError) -> Self {
        Self::Config(e)
    }
}

impl From<InputError> for SetupError {
    fn from(e: InputError) -> Self {
        Self::Start(e)
    }
}

error_enum! {
    /// A tree operation that could not be carried out; the tree is unchanged.
    pub enum TreeError {
        /// The arena holds its capacity of nodes.
        Full => "tree arena full",
        /// The id does not name a node of this tree.
        UnknownNode => "unknown node id",
        /// The new parent lies in the child's own subtree: the edge would close a cycle.
        WouldCycle => "edge would create a cycle",
        /// The caller's buffer is too small for the path.
        BufferTooSmall => "path buffer too small",
        /// The node has children, or is the root: only a leaf can be removed.
        NotALeaf => "only a leaf that is not the root can be removed",
    }
}

error_enum! {
    /// A dynamic-obstacle operation that could not be carried out; the set is unchanged.
    pub enum ObstacleError {
        /// The set holds its capacity of obstacles.
        Full => "obstacle set full",
        /// No obstacle has this id (never added, or already removed).
        UnknownId => "unknown obstacle id",
        /// Centre not finite, or radius not finite and positive.
        BadCircle => "circle centre must be finite and radius finite and positive",
    }
}

error_enum! {
    /// A spatial-index operation that could not be carried out; the index is unchanged.
    pub enum IndexError {
        /// The node id is not below the index's capacity.
        IdOutOfRange => "node id beyond the index capacity",
        /// The node is already in the index (insert) or not in it (remove).
        Membership => "node already present (insert) or absent (remove)",
        /// The position is not finite.
        NotFinite => "position is NaN or infinite",
    }
}

error_enum! {
    /// Why a roadmap (`roadmap::Roadmap`, feature `roadmap`) was refused.
    pub enum RoadmapError {
        /// Fewer bytes than the header, or than the sizes it announces.
        Truncated => "roadmap truncated",
        /// The magic bytes are wrong: not a roadmap.
        BadMagic => "not a roadmap (bad magic)",
        /// A format version this build cannot read.
        UnsupportedVersion => "unsupported roadmap version",
        /// A field is out of range: sizes, an edge list out of order or naming no node, a
        /// position that is not finite.
        BadHeader => "roadmap field out of range",
        /// The roadmap was baked from another map (or for another robot body) than the
        /// planner's.
        WrongMap => "the roadmap was baked from another map",
        /// The roadmap has more nodes than the reverse tree's arena has free slots (the
        /// search's scratch): at most `N - 1`.
        TooLarge => "the roadmap has more nodes than the tree arena holds (N - 1)",
    }
}

/// Why a diffusion table was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TableError {
    /// Fewer bytes than the header, or than the payload the header announces.
    Truncated,
    /// The magic bytes are wrong: not a table.
    BadMagic,
    /// A format version this build cannot read.
    UnsupportedVersion,
    /// A header field is out of range (element kind, dimensions, sizes, cell size, scale).
    BadHeader,
    /// The payload does not match its checksum.
    BadChecksum,
    /// The table was baked from another map than the one it is used with
    /// ([`DiffusionTable::check_map`](crate::metric::DiffusionTable::check_map)).
    WrongMap,
}

impl core::fmt::Display for TableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Truncated => "table truncated",
            Self::BadMagic => "not a diffusion table (bad magic)",
            Self::UnsupportedVersion => "unsupported table version",
            Self::BadHeader => "table header out of range",
            Self::BadChecksum => "table checksum mismatch",
            Self::WrongMap => {
                "the table was baked from another map (its size, cell size or contents differ)"
            }
        })
    }
}

impl core::error::Error for TableError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_is_a_sentence() {
        use core::fmt::Write;
        let mut s = heapless::String::<64>::new();
        write!(s, "{}", TreeError::Full).unwrap();
        assert_eq!(s, "tree arena full");
        let e: &dyn core::error::Error = &InputError::NotFinite;
        s.clear();
        write!(s, "{e}").unwrap();
        assert!(s.contains("NaN"));
    }
}
