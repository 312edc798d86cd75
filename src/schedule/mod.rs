//! CSV schedules: pours, cooling, grouting, weather, reservoir.
