//! Compressed glTF (#18 point 5): meshopt-compressed and quantized copies of the default scene,
//! made here with the `meshopt` crate's encoders, load the same triangles and render the same
//! image as the original.

use gi_lab_tests::meshopt_copy::meshopt_copy;
use gi_lab_tests::{gpu, read};
use gi_render::scene::cornell::DEFAULT_SCENE_GLB;
use gi_render::scene::{LoadOptions, Scene, load_gltf_bytes};
use gi_render::{LabSettings, Renderer, metrics};

/// The triangles of an index list, each rotated to start at its smallest index (meshopt's
/// index codec may rotate a triangle's corners; it keeps their cyclic order, so the winding).
fn triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .chunks_exact(3)
        .map(|t| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect()
}

fn load(glb: &[u8]) -> Scene {
    load_gltf_bytes(glb, None, &LoadOptions::default()).unwrap_or_else(|e| panic!("the copy loads: {e}"))
}

/// The tone-mapped-free final image of `scene` after four paused frames of the default
/// technique (instant radiosity with ISMs, which depends on every vertex through the G-buffer,
/// the VPL sampling and the ISM point cloud).
fn render(scene: Scene) -> gi_render::ImageF32 {
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 96, 96).expect("renderer");
    r.clock.playing = false;
    for _ in 0..4 {
        r.render_frame();
    }
    read(&r, "final.hdr")
}

#[test]
fn a_meshopt_copy_of_the_default_scene_loads_the_same_triangles_and_renders_the_same_image() {
    let copy = meshopt_copy(DEFAULT_SCENE_GLB, false);
    assert!(
        copy.len() < DEFAULT_SCENE_GLB.len(),
        "the copy is compressed: {} bytes vs {}",
        copy.len(),
        DEFAULT_SCENE_GLB.len()
    );
    let (a, b) = (load(DEFAULT_SCENE_GLB), load(&copy));
    assert!(b.warnings.is_empty(), "no warning for the meshopt extension: {:?}", b.warnings);
    assert_eq!(a.triangle_count(), b.triangle_count());
    assert_eq!(a.meshes.len(), b.meshes.len());
    for (ma, mb) in a.meshes.iter().zip(&b.meshes) {
        assert_eq!(ma.primitives.len(), mb.primitives.len(), "mesh {}", ma.name);
        for (pa, pb) in ma.primitives.iter().zip(&mb.primitives) {
            // The vertex and index codecs are lossless: bit-identical vertices, the same
            // triangles in the same order and winding.
            assert_eq!(triangles(&pa.indices), triangles(&pb.indices), "mesh {}", ma.name);
            assert_eq!(pa.vertices, pb.vertices, "mesh {}", ma.name);
        }
    }
    // Rendered with the corners as the codec rotated them, the original is the same image
    // bit for bit: materials, nodes, lights and cameras came through unchanged.
    let mut rotated = a.clone();
    for (ma, mb) in rotated.meshes.iter_mut().zip(&b.meshes) {
        for (pa, pb) in ma.primitives.iter_mut().zip(&mb.primitives) {
            pa.indices.clone_from(&pb.indices);
        }
    }
    let (ib, ir) = (render(b), render(rotated));
    let max =
        ib.data.iter().zip(&ir.data).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max);
    assert_eq!(max, 0.0, "the copy renders the image of the original with the same corners");
    // With the original corners the image differs only where a triangle's corner order
    // matters (the ISM point cloud's barycentric samples, rasterisation ties): measured
    // FLIP 0.0013 at 96², bound 0.002.
    let (flip, _) = metrics::flip(&ib, &render(a)).expect("flip");
    assert!(flip < 0.002, "the copy renders the original's image: FLIP {flip}");
}

#[test]
fn a_quantized_copy_with_octahedral_normals_renders_like_the_original() {
    let copy = meshopt_copy(DEFAULT_SCENE_GLB, true);
    let (a, b) = (load(DEFAULT_SCENE_GLB), load(&copy));
    assert!(b.warnings.is_empty(), "no warning for KHR_mesh_quantization: {:?}", b.warnings);
    let mut worst = 0.0f32;
    for (ma, mb) in a.meshes.iter().zip(&b.meshes) {
        for (pa, pb) in ma.primitives.iter().zip(&mb.primitives) {
            assert_eq!(triangles(&pa.indices), triangles(&pb.indices));
            for (va, vb) in pa.vertices.iter().zip(&pb.vertices) {
                assert_eq!(va.position, vb.position);
                let (na, nb) = (glam::Vec3::from(va.normal), glam::Vec3::from(vb.normal));
                worst = worst.max(na.angle_between(nb));
            }
        }
    }
    // 8-bit octahedral normals: 2 / 127 of the octahedron's side, under a degree.
    assert!(worst.to_degrees() < 1.0, "normals within a degree of the originals, worst {}°", worst.to_degrees());
    let (ia, ib) = (render(a), render(b));
    let (flip, _) = metrics::flip(&ib, &ia).expect("flip");
    // Measured FLIP 0.0021 at 96² (corner rotation as above, and the normals), bound 0.003.
    assert!(flip < 0.003, "the quantized copy renders like the original: FLIP {flip}");
}
