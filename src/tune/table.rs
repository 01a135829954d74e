//! The text table of a tuning (`momentlab tune`'s output): per target the chosen setting, the
//! best, the runner-up and the gain over the published defaults, each with its error split
//! into leak, darkening and noise.

use super::{Scored, Tuning};

fn pct(x: f64) -> String {
    format!("{:.3}%", 100.0 * x)
}

fn row(scene: &str, s: &Scored) -> String {
    format!(
        "{:<8} {:<48} {:>5} {:>8.1} {:>8} {:>8} {:>8} {:>8} {:>8}",
        scene,
        s.label,
        s.bits_per_texel,
        s.ns_per_fragment,
        pct(s.error),
        pct(s.leak),
        pct(s.darkening),
        pct(s.noise),
        pct(s.noise_share)
    )
}

/// The text table of a tuning: per target the chosen setting, the best, the runner-up and the
/// gain over the published defaults.
pub fn table(t: &Tuning) -> String {
    let mut out = format!(
        "{:<8} {:<48} {:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}\n",
        "scene", "setting", "bits", "GPU ns", "error", "leak", "darken", "noise", ">1/255"
    );
    for target in t.scenes.iter().chain(std::iter::once(&t.overall)) {
        out += &row(&target.scene, &target.chosen);
        out += "   ← chosen";
        match super::export::glsl_lines(&target.chosen.setting) {
            Ok(n) if n > super::export::EXPORT_LINES_BOUND => {
                out += &format!(
                    " (export {n} lines of GLSL, above the {} bound)",
                    super::export::EXPORT_LINES_BOUND
                )
            }
            _ => {}
        }
        out += "\n";
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
                "{:<8}   vs {:<40} error {:>8}{}: tuned gains {:+.3} ± {:.3} pp\n",
                "",
                r.name,
                pct(r.scored.error),
                if r.scored.feasible {
                    String::new()
                } else {
                    format!(" (noise above 1/255 on {})", pct(r.scored.noise_share))
                },
                100.0 * r.gain.mean,
                100.0 * r.gain.half_width
            );
        }
    }
    out += &format!(
        "(error = leak + darkening + noise against exact moments; feasible: noise above 1/255 on at most {} of fragments; tolerance {} absolute; {} fragments per scene, {} settings screened on {} per scene, {} confirmed; 95 % paired intervals; {:.1} s)\n",
        pct(t.max_noise),
        pct(t.tolerance),
        t.fragments_per_scene,
        t.settings_screened,
        t.screen_per_scene,
        t.settings_confirmed,
        t.seconds
    );
    out
}
