//! The scenes that ship with the engine, built into the binary so a copied
//! or installed `engine` finds them wherever it runs (no build-folder paths).

/// `(name, scene file text)`, as in `assets/scenes/<name>.toml`.
pub const SHIPPED: &[(&str, &str)] = &[
    ("teapot", include_str!("../../../assets/scenes/teapot.toml")),
    (
        "teapot_split",
        include_str!("../../../assets/scenes/teapot_split.toml"),
    ),
    (
        "teapot_rings",
        include_str!("../../../assets/scenes/teapot_rings.toml"),
    ),
    ("glass", include_str!("../../../assets/scenes/glass.toml")),
    (
        "glass_near",
        include_str!("../../../assets/scenes/glass_near.toml"),
    ),
    ("brass", include_str!("../../../assets/scenes/brass.toml")),
];

/// The text of the shipped scene `name`, if there is one.
pub fn shipped(name: &str) -> Option<&'static str> {
    SHIPPED.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// The shipped scenes' names, for "did you mean" messages.
pub fn shipped_names() -> String {
    SHIPPED
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Scene `text` without its views above the orbit plane: its
/// `neighbour_above*` lines and its rings (`rings`, `ring_step_deg`,
/// `ring_line_every`), so small scenes derived from the shipped teapot
/// (tests) are 1D orbits that trace nothing above the plane.
pub fn without_views_above(text: &str) -> String {
    const ABOVE: [&str; 4] = [
        "neighbour_above",
        "rings =",
        "ring_step_deg =",
        "ring_line_every =",
    ];
    let lines = text
        .lines()
        .filter(|l| !ABOVE.iter().any(|k| l.trim_start().starts_with(k)));
    lines.map(|l| format!("{l}\n")).collect()
}
