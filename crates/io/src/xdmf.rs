//! XDMF pieces shared by the point writers (grains, material points).

use std::fmt::Write;

/// A uniform Polyvertex grid of `n` points of group `group` in HDF5 file `file`, named
/// `name`, without its closing tag: geometry from `position` (n × 3), then one node
/// attribute per entry of `datasets` after the first (name, components: 1 scalar, 3 vector,
/// 9 tensor, else matrix), then `id`. `pad` indents every line. The caller closes the `<Grid>`.
pub fn open_points_grid(
    s: &mut String,
    pad: &str,
    name: &str,
    (file, group, n): (&str, &str, u64),
    datasets: &[(&str, usize, &str)],
) {
    let item = |dims: &str, kind: &str, path: &str| {
        format!("<DataItem Dimensions=\"{dims}\" NumberType=\"{kind}\" Precision=\"8\" Format=\"HDF\">{file}:/{group}/{path}</DataItem>")
    };
    let _ = write!(
        s,
        "{pad}<Grid Name=\"{name}\" GridType=\"Uniform\">\n{pad} <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{n}\"/>\n{pad} <Geometry GeometryType=\"XYZ\">\n{pad}  {}\n{pad} </Geometry>\n",
        item(&format!("{n} 3"), "Float", "position")
    );
    let attrs = datasets.iter().skip(1).map(|&(a, c, _)| (a, c, "Float"));
    for (attr, comps, kind) in attrs.chain([("id", 1, "UInt")]) {
        let (shape, dims) = match comps {
            1 => ("Scalar", format!("{n}")),
            3 => ("Vector", format!("{n} 3")),
            9 => ("Tensor", format!("{n} 9")),
            c => ("Matrix", format!("{n} {c}")),
        };
        let _ = write!(
            s,
            "{pad} <Attribute Name=\"{attr}\" AttributeType=\"{shape}\" Center=\"Node\">\n{pad}  {}\n{pad} </Attribute>\n",
            item(&dims, kind, attr)
        );
    }
}
