//! Measured rods (`[effects] rod_properties_csv`, issue 6): the rods the
//! scene's table names get its EA/EI (GJ, GA) instead of the nominal tube
//! section — the scatter of composite tubes the paper's discussion raises.
//! The table's format and the rod names: [`crate::scene::RodProperties`].

use super::{record, Effect, EffectKind};
use crate::mechanics::Section;
use crate::scene::{RodProperties, Scene, TrussRod};

/// The effect of a measured-rods table.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredRods {
    /// The table, read and validated with the scene.
    pub table: RodProperties,
}

impl MeasuredRods {
    /// The effect, when the scene names a table.
    pub fn of(scene: &Scene) -> Option<Self> {
        let table = scene.effects.rod_properties.clone()?;
        record(EffectKind::RodProperties);
        Some(MeasuredRods { table })
    }
}

impl Effect for MeasuredRods {
    fn name(&self) -> &str {
        "measured rods"
    }

    fn rod_section(&self, rod: TrussRod, section: Section) -> Section {
        self.table.section(rod, &section)
    }
}
