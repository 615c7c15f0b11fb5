//! VTK XML PolyData (`.vtp`) particle frames and the `.pvd` collection that ParaView opens as a
//! time series.
//!
//! Each particle is a vertex cell. Point data (selectable with `output.fields`): `stress` (full
//! 3×3 Cauchy tensor, Pa, tension positive, σ_zz of plane strain included), `pressure` (mean
//! stress tr σ/3, Pa), `velocity` and `displacement` (3 components, z = 0 in 2D), `plastic_strain`
//! (ε̄ᵖ), `body` and `material` (indices), `density` (kg/m³). Full f64 precision in every
//! format (`output.vtk_format`):
//!
//! - `binary`: `format="appended"` arrays in one `<AppendedData encoding="raw">` section after
//!   the XML. Each array's `offset` counts bytes from the first byte after the `_`; there a
//!   UInt64 byte count (`header_type="UInt64"`) precedes the little-endian values.
//! - `compressed`: the same with `compressor="vtkZLibDataCompressor"`: each array is cut into
//!   blocks of [`BLOCK`] bytes (the last may be shorter), each compressed with zlib, preceded
//!   by the UInt64 header `[blocks, BLOCK, bytes of a partial last block or 0, compressed size
//!   of each block...]`.
//! - `ascii`: decimal text inside each `<DataArray>`.

use std::fmt::Write as _;
use std::io::Write as _;

use flate2::Compression;
use flate2::write::ZlibEncoder;
use mpm_constitutive::SymTensor;
use mpm_scene::SceneModel;
use mpm_scene::file::{VtkField, VtkFormat};
use mpm_solver::Particles;
use rayon::prelude::*;

/// uncompressed bytes per zlib block of the `compressed` format.
pub const BLOCK: usize = 1 << 20;

/// zlib level of the `compressed` format (1 = fastest; higher levels gain a few per cent of
/// size on particle data at several times the cost).
const LEVEL: u32 = 1;

/// A frame's bytes: the XML (with `<AppendedData encoding="raw">_` at its end for the binary
/// formats), the appended arrays and the closing tags, written one after the other.
pub struct Frame {
    /// the XML head.
    pub xml: String,
    /// the appended binary arrays (empty for ASCII).
    pub data: Vec<u8>,
    /// the closing tags.
    pub tail: &'static str,
}

impl Frame {
    /// the parts in file order.
    pub fn parts(&self) -> [&[u8]; 3] {
        [self.xml.as_bytes(), &self.data, self.tail.as_bytes()]
    }
}

/// A value type of a data array.
trait Scalar: Copy + std::fmt::Display {
    /// the VTK type name.
    const TYPE: &'static str;
    /// appends the little-endian bytes.
    fn put(self, out: &mut Vec<u8>);
}

impl Scalar for f64 {
    const TYPE: &'static str = "Float64";
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Scalar for i32 {
    const TYPE: &'static str = "Int32";
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Scalar for i64 {
    const TYPE: &'static str = "Int64";
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

/// Writes data arrays in one of the formats.
struct Arrays {
    format: VtkFormat,
    xml: String,
    /// the appended section (binary formats).
    data: Vec<u8>,
    /// one array's raw bytes before compression.
    raw: Vec<u8>,
}

impl Arrays {
    fn array<T: Scalar>(
        &mut self,
        name: &str,
        components: usize,
        count: usize,
        values: impl Iterator<Item = T>,
    ) -> std::io::Result<()> {
        let ty = T::TYPE;
        if self.format == VtkFormat::Ascii {
            ascii_array(&mut self.xml, ty, name, components, values);
            return Ok(());
        }
        let _ = writeln!(
            self.xml,
            "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"appended\" offset=\"{}\"/>",
            self.data.len()
        );
        let bytes = count * components * size_of::<T>();
        if self.format == VtkFormat::Binary {
            self.data.reserve(8 + bytes);
            self.data.extend_from_slice(&(bytes as u64).to_le_bytes());
            let start = self.data.len();
            values.for_each(|v| v.put(&mut self.data));
            debug_assert_eq!(self.data.len() - start, bytes);
            return Ok(());
        }
        self.raw.clear();
        self.raw.reserve(bytes);
        values.for_each(|v| v.put(&mut self.raw));
        let blocks: Vec<Vec<u8>> = self
            .raw
            .par_chunks(BLOCK)
            .map(|block| {
                let mut z =
                    ZlibEncoder::new(Vec::with_capacity(block.len() / 2), Compression::new(LEVEL));
                z.write_all(block)?;
                z.finish()
            })
            .collect::<std::io::Result<_>>()?;
        let partial = self.raw.len() % BLOCK;
        let header = [blocks.len(), BLOCK, partial].into_iter().chain(blocks.iter().map(Vec::len));
        for h in header {
            self.data.extend_from_slice(&(h as u64).to_le_bytes());
        }
        for b in &blocks {
            self.data.extend_from_slice(b);
        }
        Ok(())
    }
}

/// an ASCII `<DataArray>` element, values separated by spaces on lines of about 4000 bytes.
fn ascii_array<T: Scalar>(
    out: &mut String,
    ty: &str,
    name: &str,
    components: usize,
    values: impl Iterator<Item = T>,
) {
    let _ = writeln!(
        out,
        "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"ascii\">"
    );
    let mut line = String::new();
    for (k, v) in values.enumerate() {
        if k > 0 {
            line.push(' ');
        }
        let _ = write!(line, "{v}");
        if line.len() > 4000 {
            let _ = writeln!(out, "          {line}");
            line.clear();
        }
    }
    if !line.is_empty() {
        let _ = writeln!(out, "          {line}");
    }
    out.push_str("        </DataArray>\n");
}

/// The per-particle values a frame writes, from the particles of either build of the solver
/// (plane strain: z = 0 and the plane-strain σ_zz; 3D: everything as it is).
pub trait FrameData: Sync {
    /// number of particles.
    fn len(&self) -> usize;
    /// whether there is no particle.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// position (m).
    fn position(&self, i: usize) -> [f64; 3];
    /// velocity (m/s).
    fn velocity(&self, i: usize) -> [f64; 3];
    /// displacement from the initial position (m).
    fn displacement(&self, i: usize) -> [f64; 3];
    /// the full Cauchy stress (Pa, tension positive).
    fn stress(&self, i: usize) -> SymTensor;
    /// equivalent plastic strain ε̄ᵖ.
    fn plastic_strain(&self, i: usize) -> f64;
    /// body index.
    fn body(&self, i: usize) -> u16;
    /// material index.
    fn material(&self, i: usize) -> u16;
    /// density (kg/m³).
    fn density(&self, i: usize) -> f64;
}

/// a scene model's equivalent plastic strain of particle state `state` of material `m`.
fn plastic<M: SceneModel>(materials: &[M], m: u16, state: &M::State) -> f64 {
    materials.get(usize::from(m)).map_or(0.0, |mat| mat.equivalent_plastic_strain(state))
}

/// The plane-strain solver's particles as frame data.
struct Plane<'a, M: SceneModel> {
    p: &'a Particles<M::State>,
    materials: &'a [M],
}

impl<M: SceneModel> FrameData for Plane<'_, M> {
    fn len(&self) -> usize {
        self.p.len()
    }
    fn position(&self, i: usize) -> [f64; 3] {
        let x = self.p.position[i];
        [x.x, x.y, 0.0]
    }
    fn velocity(&self, i: usize) -> [f64; 3] {
        let v = self.p.velocity[i];
        [v.x, v.y, 0.0]
    }
    fn displacement(&self, i: usize) -> [f64; 3] {
        let u = self.p.position[i] - self.p.initial_position[i];
        [u.x, u.y, 0.0]
    }
    fn stress(&self, i: usize) -> SymTensor {
        self.p.stress[i].to_sym()
    }
    fn plastic_strain(&self, i: usize) -> f64 {
        plastic(self.materials, self.p.material[i], &self.p.state[i])
    }
    fn body(&self, i: usize) -> u16 {
        self.p.body[i]
    }
    fn material(&self, i: usize) -> u16 {
        self.p.material[i]
    }
    fn density(&self, i: usize) -> f64 {
        self.p.density(i)
    }
}

/// The 3D solver's particles as frame data.
struct Space<'a, M: SceneModel> {
    p: &'a mpm_solver3d::Particles<M::State>,
    materials: &'a [M],
}

impl<M: SceneModel> FrameData for Space<'_, M> {
    fn len(&self) -> usize {
        self.p.len()
    }
    fn position(&self, i: usize) -> [f64; 3] {
        self.p.position[i].to_array()
    }
    fn velocity(&self, i: usize) -> [f64; 3] {
        self.p.velocity[i].to_array()
    }
    fn displacement(&self, i: usize) -> [f64; 3] {
        (self.p.position[i] - self.p.initial_position[i]).to_array()
    }
    fn stress(&self, i: usize) -> SymTensor {
        self.p.stress[i]
    }
    fn plastic_strain(&self, i: usize) -> f64 {
        plastic(self.materials, self.p.material[i], &self.p.state[i])
    }
    fn body(&self, i: usize) -> u16 {
        self.p.body[i]
    }
    fn material(&self, i: usize) -> u16 {
        self.p.material[i]
    }
    fn density(&self, i: usize) -> f64 {
        self.p.density(i)
    }
}

/// one frame of (plane-strain) particles at time `time` (s).
pub fn frame<M: SceneModel>(
    p: &Particles<M::State>,
    materials: &[M],
    fields: &[VtkField],
    format: VtkFormat,
    time: f64,
) -> std::io::Result<Frame> {
    frame_of(&Plane { p, materials }, fields, format, time)
}

/// one frame of the 3D solver's particles at time `time` (s).
pub fn frame_3d<M: SceneModel>(
    p: &mpm_solver3d::Particles<M::State>,
    materials: &[M],
    fields: &[VtkField],
    format: VtkFormat,
    time: f64,
) -> std::io::Result<Frame> {
    frame_of(&Space { p, materials }, fields, format, time)
}

/// one frame of the particles `d` at time `time` (s).
pub fn frame_of<D: FrameData>(
    d: &D,
    fields: &[VtkField],
    format: VtkFormat,
    time: f64,
) -> std::io::Result<Frame> {
    let n = d.len();
    let binary = format != VtkFormat::Ascii;
    let mut a = Arrays {
        format,
        xml: String::with_capacity(if binary { 4000 } else { 200 + n * 200 }),
        data: Vec::with_capacity(if binary { format.frame_bytes(n, fields) as usize } else { 0 }),
        raw: Vec::new(),
    };
    let out = &mut a.xml;
    out.push_str("<?xml version=\"1.0\"?>\n");
    match format {
        VtkFormat::Ascii => out.push_str(
            "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n",
        ),
        VtkFormat::Binary => out.push_str(
            "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        ),
        VtkFormat::Compressed => out.push_str(
            "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n",
        ),
    }
    out.push_str("  <PolyData>\n    <FieldData>\n");
    let _ = writeln!(
        out,
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time}</DataArray>"
    );
    out.push_str("    </FieldData>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    out.push_str("      <PointData>\n");
    for &field in fields {
        match field {
            VtkField::Stress => a.array(
                "stress",
                9,
                n,
                (0..n)
                    .map(|i| d.stress(i))
                    .flat_map(|s| [s.xx, s.xy, s.zx, s.xy, s.yy, s.yz, s.zx, s.yz, s.zz]),
            )?,
            VtkField::Pressure => {
                a.array("pressure", 1, n, (0..n).map(|i| d.stress(i).trace() / 3.0))?;
            }
            VtkField::Velocity => {
                a.array("velocity", 3, n, (0..n).flat_map(|i| d.velocity(i)))?;
            }
            VtkField::Displacement => {
                a.array("displacement", 3, n, (0..n).flat_map(|i| d.displacement(i)))?;
            }
            VtkField::PlasticStrain => {
                a.array("plastic_strain", 1, n, (0..n).map(|i| d.plastic_strain(i)))?;
            }
            VtkField::Body => a.array("body", 1, n, (0..n).map(|i| i32::from(d.body(i))))?,
            VtkField::Material => {
                a.array("material", 1, n, (0..n).map(|i| i32::from(d.material(i))))?;
            }
            VtkField::Density => a.array("density", 1, n, (0..n).map(|i| d.density(i)))?,
        }
    }
    a.xml.push_str("      </PointData>\n      <Points>\n");
    a.array("position", 3, n, (0..n).flat_map(|i| d.position(i)))?;
    a.xml.push_str("      </Points>\n      <Verts>\n");
    a.array("connectivity", 1, n, 0..n as i64)?;
    a.array("offsets", 1, n, 1..=n as i64)?;
    a.xml.push_str("      </Verts>\n    </Piece>\n  </PolyData>\n");
    let tail = if binary {
        a.xml.push_str("  <AppendedData encoding=\"raw\">\n   _");
        "\n  </AppendedData>\n</VTKFile>\n"
    } else {
        a.xml.push_str("</VTKFile>\n");
        ""
    };
    Ok(Frame { xml: a.xml, data: a.data, tail })
}

/// the ParaView collection of `frames` (time, file relative to the `.pvd`).
pub fn pvd(frames: &[(f64, String)]) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <Collection>\n");
    for (t, file) in frames {
        let _ =
            writeln!(out, "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{file}\"/>");
    }
    out.push_str("  </Collection>\n</VTKFile>\n");
    out
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::io::Read;

    use mpm_constitutive::{LinearElastic, PlaneTensor};
    use mpm_solver::{NewParticle, Vector};

    use super::*;

    /// 2¹⁷ particles: the 8-byte arrays fill exactly one block, positions exactly three, stress
    /// nine and a partial one.
    const N: usize = 1 << 17;

    fn particles() -> Particles<()> {
        let mut p = Particles::with_capacity(N);
        for i in 0..N {
            let s = i as f64;
            p.push(NewParticle {
                position: Vector::new(0.1 * s.sqrt(), (0.37 * s).sin()),
                velocity: Vector::new(1e-3 * s, -2.5),
                volume: 1e-4 * (1.0 + (s * 0.01).cos().abs()),
                density: 1600.0,
                stress: PlaneTensor::new(-1.5 * s - 0.1, -s / 3.0, 0.3 * s, s.cbrt()),
                state: (),
                material: (i % 3) as u16,
                body: (i % 7) as u16,
            });
        }
        // displacements and velocities that are not round numbers
        for (i, x) in p.position.iter_mut().enumerate() {
            *x += Vector::new(1e-7 * i as f64, -std::f64::consts::PI * 1e-5);
        }
        p
    }

    fn write(p: &Particles<()>, format: VtkFormat) -> Vec<u8> {
        let materials = vec![LinearElastic::from_young_poisson(1e6, 0.3).unwrap(); 3];
        let frame = frame(p, &materials, &VtkField::ALL, format, 0.125).unwrap();
        frame.parts().concat()
    }

    #[derive(Debug, PartialEq)]
    enum Values {
        F64(Vec<f64>),
        I32(Vec<i32>),
        I64(Vec<i64>),
    }

    /// the value of attribute `name` in the element text `tag`.
    fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
        let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        let len = tag[start..].find('"')?;
        Some(&tag[start..start + len])
    }

    fn typed(ty: &str, bytes: &[u8]) -> Values {
        match ty {
            "Float64" => Values::F64(
                bytes.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect(),
            ),
            "Int32" => Values::I32(
                bytes.chunks_exact(4).map(|c| i32::from_le_bytes(c.try_into().unwrap())).collect(),
            ),
            "Int64" => Values::I64(
                bytes.chunks_exact(8).map(|c| i64::from_le_bytes(c.try_into().unwrap())).collect(),
            ),
            _ => panic!("unexpected type {ty}"),
        }
    }

    fn u64_at(data: &[u8], at: usize) -> usize {
        u64::from_le_bytes(data[at..at + 8].try_into().unwrap()) as usize
    }

    /// decodes every array of a frame the way a VTK reader does: (type, components, values)
    /// by name, reading appended arrays at their offsets.
    fn decode(file: &[u8]) -> BTreeMap<String, (usize, Values)> {
        let marker = b"<AppendedData encoding=\"raw\">";
        let appended = file.windows(marker.len()).position(|w| w == marker);
        let xml_end = appended.unwrap_or(file.len());
        let xml = std::str::from_utf8(&file[..xml_end]).unwrap();
        let data = appended.map(|a| {
            let underscore = a + file[a..].iter().position(|&b| b == b'_').unwrap();
            &file[underscore + 1..]
        });
        let root = &xml[xml.find("<VTKFile").unwrap()..];
        let root = &root[..root.find('>').unwrap()];
        let compressed = attr(root, "compressor") == Some("vtkZLibDataCompressor");
        let mut out = BTreeMap::new();
        let mut ends = Vec::new();
        for piece in xml.split("<DataArray").skip(1) {
            let tag = &piece[..piece.find('>').unwrap()];
            let name = attr(tag, "Name").unwrap().to_string();
            let ty = attr(tag, "type").unwrap();
            let components: usize = attr(tag, "NumberOfComponents").unwrap_or("1").parse().unwrap();
            let values = match attr(tag, "format").unwrap() {
                "ascii" => {
                    let body = &piece[tag.len() + 1..piece.find("</DataArray>").unwrap()];
                    let words = body.split_whitespace();
                    match ty {
                        "Float64" => Values::F64(words.map(|w| w.parse().unwrap()).collect()),
                        "Int32" => Values::I32(words.map(|w| w.parse().unwrap()).collect()),
                        "Int64" => Values::I64(words.map(|w| w.parse().unwrap()).collect()),
                        _ => panic!("unexpected type {ty}"),
                    }
                }
                "appended" => {
                    assert_eq!(attr(root, "header_type"), Some("UInt64"));
                    let data = data.unwrap();
                    let offset: usize = attr(tag, "offset").unwrap().parse().unwrap();
                    if compressed {
                        let blocks = u64_at(data, offset);
                        let block = u64_at(data, offset + 8);
                        let partial = u64_at(data, offset + 16);
                        let mut at = offset + 24 + 8 * blocks;
                        let mut raw = Vec::new();
                        for k in 0..blocks {
                            let size = u64_at(data, offset + 24 + 8 * k);
                            let mut inflated = Vec::new();
                            flate2::read::ZlibDecoder::new(&data[at..at + size])
                                .read_to_end(&mut inflated)
                                .unwrap();
                            let full = k + 1 < blocks || partial == 0;
                            assert_eq!(inflated.len(), if full { block } else { partial });
                            raw.extend_from_slice(&inflated);
                            at += size;
                        }
                        ends.push(at);
                        typed(ty, &raw)
                    } else {
                        let bytes = u64_at(data, offset);
                        ends.push(offset + 8 + bytes);
                        typed(ty, &data[offset + 8..offset + 8 + bytes])
                    }
                }
                f => panic!("unexpected format {f}"),
            };
            out.insert(name, (components, values));
        }
        if let Some(data) = data {
            // the arrays follow each other without gaps up to the closing tags
            let last = ends.iter().copied().max().unwrap();
            assert_eq!(&data[last..], b"\n  </AppendedData>\n</VTKFile>\n");
        }
        out
    }

    fn check_values(arrays: &BTreeMap<String, (usize, Values)>, p: &Particles<()>) {
        let f64s = |name: &str, components: usize| match &arrays[name] {
            (c, Values::F64(v)) if *c == components => v.clone(),
            other => panic!("{name}: {other:?}"),
        };
        let points: Vec<f64> = p.position.iter().flat_map(|x| [x.x, x.y, 0.0]).collect();
        assert_eq!(f64s("position", 3).len(), 3 * N);
        assert!(f64s("position", 3).iter().zip(&points).all(|(a, b)| a.to_bits() == b.to_bits()));
        let stress: Vec<f64> = p
            .stress
            .iter()
            .flat_map(|s| [s.xx, s.xy, 0.0, s.xy, s.yy, 0.0, 0.0, 0.0, s.zz])
            .collect();
        let got = f64s("stress", 9);
        assert_eq!(got.len(), 9 * N);
        assert!(got.iter().zip(&stress).all(|(a, b)| a.to_bits() == b.to_bits()));
        let velocity: Vec<f64> = p.velocity.iter().flat_map(|v| [v.x, v.y, 0.0]).collect();
        assert_eq!(f64s("velocity", 3), velocity);
        let u: Vec<f64> = p
            .position
            .iter()
            .zip(&p.initial_position)
            .flat_map(|(x, x0)| [x.x - x0.x, x.y - x0.y, 0.0])
            .collect();
        assert_eq!(f64s("displacement", 3), u);
        let pressure: Vec<f64> = p.stress.iter().map(|s| s.trace() / 3.0).collect();
        assert_eq!(f64s("pressure", 1), pressure);
        assert_eq!(f64s("density", 1), (0..N).map(|i| p.density(i)).collect::<Vec<_>>());
        assert_eq!(f64s("plastic_strain", 1), vec![0.0; N]);
        let ids = |v: &[u16]| Values::I32(v.iter().map(|&b| i32::from(b)).collect());
        assert_eq!(arrays["body"], (1, ids(&p.body)));
        assert_eq!(arrays["material"], (1, ids(&p.material)));
        assert_eq!(arrays["connectivity"], (1, Values::I64((0..N as i64).collect())));
        assert_eq!(arrays["offsets"], (1, Values::I64((1..=N as i64).collect())));
        assert_eq!(arrays["TimeValue"], (1, Values::F64(vec![0.125])));
    }

    #[test]
    fn binary_frames_decode_to_the_particle_values() {
        let p = particles();
        let file = write(&p, VtkFormat::Binary);
        let head = String::from_utf8_lossy(&file[..400]);
        assert!(head.contains("version=\"1.0\"") && head.contains("header_type=\"UInt64\""));
        assert!(!head.contains("compressor"));
        let arrays = decode(&file);
        check_values(&arrays, &p);
        // the file is its values (8 bytes, 4 for the ids) plus the XML and array headers:
        // stress, pressure, velocity, displacement, plastic strain, density, points,
        // connectivity, offsets; body, material
        let per_particle = (9 + 1 + 3 + 3 + 1 + 1 + 3 + 1 + 1) * 8 + 2 * 4;
        assert!(file.len() >= N * per_particle, "{} bytes", file.len());
        assert!(file.len() - N * per_particle < 4000, "{} bytes", file.len());
    }

    #[test]
    fn compressed_frames_inflate_to_the_particle_values() {
        let p = particles();
        let file = write(&p, VtkFormat::Compressed);
        let head = String::from_utf8_lossy(&file[..400]);
        assert!(head.contains("compressor=\"vtkZLibDataCompressor\""));
        check_values(&decode(&file), &p);
        assert!(file.len() < write(&p, VtkFormat::Binary).len());
    }

    #[test]
    fn ascii_frames_parse_to_the_same_numbers() {
        let p = particles();
        let ascii = write(&p, VtkFormat::Ascii);
        assert!(std::str::from_utf8(&ascii).is_ok());
        assert!(!String::from_utf8_lossy(&ascii).contains("AppendedData"));
        let arrays = decode(&ascii);
        check_values(&arrays, &p);
        assert_eq!(arrays, decode(&write(&p, VtkFormat::Binary)));
    }

    #[test]
    fn frame_size_estimates_follow_the_format() {
        let p = particles();
        let binary = write(&p, VtkFormat::Binary).len() as f64;
        let estimate = VtkFormat::Binary.frame_bytes(N, &VtkField::ALL) as f64;
        assert!((estimate / binary - 1.0).abs() < 0.01, "{estimate} vs {binary}");
        let only = [VtkField::Body];
        assert!(
            VtkFormat::Binary.frame_bytes(N, &only)
                < VtkFormat::Binary.frame_bytes(N, &VtkField::ALL)
        );
    }
}
