//! `vkbrdf bench`'s sustained-kernel table: each scenario's kernel on many tuples beside the
//! device copy kernel moving the same bytes (and PyTorch's device copy, where it ran).

use vkbrdf::bench::peers;

/// The sustained kernel of one scenario beside the device copy kernel moving the same bytes.
#[derive(serde::Serialize)]
pub(super) struct BandwidthRow {
    pub(super) scenario: String,
    pub(super) tuples: usize,
    pub(super) resident_tuples: usize,
    pub(super) bytes_per_tuple: usize,
    pub(super) clock: vkbrdf::gpu::KernelClock,
    pub(super) kernel_evals_per_s: f64,
    pub(super) kernel_bytes_per_s: f64,
    pub(super) copy_bytes_per_s: f64,
    /// Kernel bytes/s over copy bytes/s.
    pub(super) fraction_of_copy: f64,
}

/// Prints the sustained-kernel rows beside the copy kernel (and PyTorch's copy, when run).
pub(super) fn print_bandwidth(rows: &[BandwidthRow], peers: &[peers::PeerRow]) {
    let Some(first) = rows.first() else { return };
    outln!(
        "\nsustained kernel vs device copy kernel ({} tuples, {} resident, clock: {:?}):",
        first.tuples,
        first.resident_tuples,
        first.clock
    );
    outln!(
        "  {:<26} {:>9} {:>12} {:>10} {:>10} {:>8}",
        "scenario",
        "B/tuple",
        "M evals/s",
        "GB/s",
        "copy GB/s",
        "of copy"
    );
    for r in rows {
        outln!(
            "  {:<26} {:>9} {:>12.1} {:>10.1} {:>10.1} {:>7.0} %",
            r.scenario,
            r.bytes_per_tuple,
            r.kernel_evals_per_s / 1e6,
            r.kernel_bytes_per_s / 1e9,
            r.copy_bytes_per_s / 1e9,
            100.0 * r.fraction_of_copy
        );
    }
    // PyTorch's device-to-device copy (52 bytes moved per tuple) as a second ceiling.
    if let Some(torch_copy) = peers
        .iter()
        .find(|p| p.name == "torch-copy")
        .and_then(|p| p.evals_per_s)
    {
        let ceiling = torch_copy * 52.0;
        outln!(
            "  torch-copy ceiling: {:.1} GB/s; as a fraction of it:",
            ceiling / 1e9
        );
        for r in rows {
            outln!(
                "    {:<26} kernel {:>4.0} %   copy kernel {:>4.0} %",
                r.scenario,
                100.0 * r.kernel_bytes_per_s / ceiling,
                100.0 * r.copy_bytes_per_s / ceiling
            );
        }
    }
}
