//! The text table of a tuning, printed by `momentlab tune`.

use super::{Scored, Tuning};

fn pct(x: f64) -> String {
    format!("{:.3}%", 100.0 * x)
}

fn row(scene: &str, s: &Scored) -> String {
    format!(
        "{:<8} {:<48} {:>5} {:>8.1} {:>8} {:>8} {:>8}",
        scene,
        s.label,
        s.bits_per_texel,
        s.ns_per_fragment,
        pct(s.error),
        pct(s.leak),
        pct(s.darkening)
    )
}

/// The text table of a tuning: per target the chosen setting, the best, the runner-up and the
/// gain over the published defaults.
pub fn table(t: &Tuning) -> String {
    let mut out = format!(
        "{:<8} {:<48} {:>5} {:>8} {:>8} {:>8} {:>8}\n",
        "scene", "setting", "bits", "ns/frag", "error", "leak", "darken"
    );
    for target in t.scenes.iter().chain(std::iter::once(&t.overall)) {
        out += &row(&target.scene, &target.chosen);
        out += "   ← chosen\n";
        out += &row("", &target.best);
        out += &format!(
            "   best (chosen − best {:+.3} ± {:.3} pp)\n",
            100.0 * target.chosen_minus_best.mean,
            100.0 * target.chosen_minus_best.half_width
        );
        if let (Some(r), Some(p)) = (&target.runner_up, &target.chosen_minus_runner_up) {
            out += &row("", r);
            out += &format!(
                "   runner-up (chosen − it {:+.3} ± {:.3} pp)\n",
                100.0 * p.mean,
                100.0 * p.half_width
            );
        }
        for r in &target.references {
            out += &format!(
                "{:<8}   vs {:<40} error {:>8}: tuned gains {:+.3} ± {:.3} pp\n",
                "",
                r.name,
                pct(r.scored.error),
                100.0 * r.gain.mean,
                100.0 * r.gain.half_width
            );
        }
    }
    out += &format!(
        "(tolerance {} absolute; {} fragments per scene, {} settings screened on {} per scene, {} confirmed; 95 % paired intervals; {:.1} s)\n",
        pct(t.tolerance),
        t.fragments_per_scene,
        t.settings_screened,
        t.screen_per_scene,
        t.settings_confirmed,
        t.seconds
    );
    out
}
