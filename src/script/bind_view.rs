//! Bindings for the live viewer: the run's `view` object. Conversions only; the work
//! is in [`crate::viewer`].

use super::api::Api;
use super::bind_document::DocHandle;
use super::bind_planning::PathHandle;
use super::convert::fail;
use super::{Context, ScriptResult};
use std::sync::Arc;

/// The script's `view`: logs to the run's viewer session (does nothing without one).
#[derive(Clone)]
pub struct ViewHandle {
    ctx: Arc<Context>,
}

impl ViewHandle {
    /// The `view` of a run.
    pub fn new(ctx: &Arc<Context>) -> Self {
        Self { ctx: ctx.clone() }
    }

    fn viewer(&self) -> &crate::viewer::Viewer {
        &self.ctx.caches.view
    }
}

pub(super) fn register(api: &mut Api) {
    api.section("Viewer", "The run's `view` object logs to the live 3D viewer (`fitup run|watch SCRIPT --view`, `--record FILE.rrd`; see docs/viewer.md). Without `--view` or `--record` every call does nothing, so scripts can keep them. Logging never waits: the viewer converts and sends on its own thread. Opened documents, component moves (`transform`, `translate`, `rotate`), `follow`, robot motions and `interferences()` are shown without any call; `view` adds what the script wants on top. The `step` timeline counts animation frames (each move, followed step or trajectory sample is one).");
    api.type_::<ViewHandle>("View");
    api.get(
        "View.live -> bool",
        "Whether a viewer session is listening (`--view` or `--record`).",
        |v: &mut ViewHandle| v.viewer().is_live(),
    );
    api.f(
        "View.show(doc: Document)",
        "Shows every component of the document at its current pose (mesh, colour; fixed parts darker) at the current step.",
        |v: &mut ViewHandle, d: DocHandle| -> ScriptResult<()> {
            v.viewer().log_document(&*d.lock()?);
            Ok(())
        },
    );
    api.f(
        "View.show(path: Path, name: string)",
        "Shows a path's key points as a 3D curve named `name` with a small frame (X red, Y green, Z blue) at each key pose (mm).",
        |v: &mut ViewHandle, p: PathHandle, name: &str| v.viewer().log_path(name, &p.0.poses),
    );
    api.f(
        "View.log(text: string)",
        "Adds a line to the recording's text log at the current step.",
        |v: &mut ViewHandle, text: &str| v.viewer().text(text),
    );
    api.f(
        "View.log(name: string, value)",
        "Adds a point to the plot `plots/NAME` at the current step (any number; units are yours).",
        |v: &mut ViewHandle, name: &str, value: rhai::Dynamic| -> ScriptResult<()> {
            let x = super::convert::num(&value, "value")?;
            if !x.is_finite() {
                return Err(fail(format!("view.log: `{name}` is not a finite number")));
            }
            v.viewer().scalar(name, x);
            Ok(())
        },
    );
    api.f(
        "View.step(n: int)",
        "Sets the `step` timeline to `n` (what is logged next shows from that step on).",
        |v: &mut ViewHandle, n: i64| v.viewer().step(n),
    );
}
