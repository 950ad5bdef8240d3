//! The link-time proof of promise 2 (no input makes the core panic): this firmware calls every
//! public entry point of the core on opaque inputs (`core::hint::black_box`), and
//! `panic-never`'s panic handler is a symbol that does not exist. The binary therefore links
//! only when the optimiser has removed every panicking branch reachable from these calls.
//!
//! Build (release, LTO): `cd firmware/panic-never && cargo build --release --target
//! thumbv7em-none-eabihf`. It is never run.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::time::Duration;

use bi_am_rrt::agent::{Protocol, run_to_goal};
use bi_am_rrt::clock::{Clock, Deadline, FakeClock};
use bi_am_rrt::index::SpatialIndex;
use bi_am_rrt::map::{ObstacleId, OccupancyGrid, pack_grid};
use bi_am_rrt::metric::{DiffusionTable, ElementKind, TableHeader, write_table};
use bi_am_rrt::tree::{NodeId, Tree};
use bi_am_rrt::{Circle, Euclidean, Map, Metric, Motion, Moving, Planner, Point, Storage};
use cortex_m_rt::entry;
#[cfg(feature = "check")]
use panic_never as _;

#[cfg(not(feature = "check"))]
#[panic_handler]
#[inline(never)]
fn on_panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {
        black_box(());
    }
}
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

fn point() -> Point {
    Point::new(black_box(1.5), black_box(2.5))
}

fn exercise_planner<M: Metric, const N: usize, const B: usize>(
    storage: &mut Storage<N, B>,
    grid: OccupancyGrid<'_>,
    overlay: &mut [u8],
    space: &mut [u8],
    field: &mut [u8],
    metric: M,
) -> u32 {
    let mut cfg = black_box(bi_am_rrt::Named::table1()[black_box(7usize) % 20].cfg);
    cfg.motion = black_box(Motion {
        agent_speed: 1.0,
        period: 0.1,
        horizon: 1.0,
        obstacle_speed: 1.5,
    });
    let _ = black_box(cfg.validate());
    let rng = XorShiftRng::seed_from_u64(black_box(1));
    // A live overlay (when the opaque buffer is long enough).
    let map = match Map::new(grid).with_overlay(overlay) {
        Ok(m) => m,
        Err(_) => Map::new(grid),
    };
    // A robot body: the live cells inflated into an opaque buffer (issue 41).
    cfg.robot_radius = black_box(0.4);
    let map = match map.with_body(cfg.robot_radius, space) {
        Ok(m) => m,
        Err(_) => Map::new(grid),
    };
    // A clearance preference (issue 41): a field into an opaque buffer, and its class.
    let map = if bi_am_rrt::clearance::clearance_field(&grid, 0.4, black_box(0.5), field).is_ok() {
        cfg.clearance_weight = black_box(2.0);
        match map.with_clearance(field) {
            Ok(m) => m,
            Err(_) => Map::new(grid),
        }
    } else {
        map
    };
    let _ = black_box(map.clearance_class(point(), point()));
    let Ok(mut p) = Planner::<_, _, N, B, 4>::new(storage, map, metric, rng, cfg, point()) else {
        return 0;
    };
    let clock = FakeClock::nanos()
        .with_work_cost(black_box(12))
        .with_step(black_box(1));
    // A roadmap (feature `roadmap`): written, read from opaque bytes, searched by the calls.
    let mut rm_bytes = [0u8; 160];
    let nodes = [point(), point()];
    let _ = bi_am_rrt::roadmap::write(
        &grid,
        &nodes,
        &[black_box(1u8), 0],
        &[0, 1, 2],
        &[1, 0],
        &mut rm_bytes,
    );
    if let Ok(rm) = bi_am_rrt::roadmap::Roadmap::from_bytes(black_box(&rm_bytes[..])) {
        let _ = black_box(p.set_roadmap(Some(rm)));
    }
    let _ = p.set_goal(point());
    let _ = p.plan(&clock, point());
    let _ = p.grow(&clock);
    let mut buf = [Point::ZERO; 16];
    let _ = black_box(p.path(&mut buf));
    if let Ok(id) = p.add_obstacle(Circle::new(point(), black_box(0.5))) {
        let _ = p.plan(&clock, point());
        let _ = p.remove_obstacle(id);
    }
    // Moving obstacles (module `motion`): added, updated, planned against.
    let walker =
        Moving::new(Circle::new(point(), black_box(0.4)), point()).trusted_for(black_box(2.0));
    if let Ok(id) = p.add_moving_obstacle(walker) {
        let _ = p.update_obstacle(id, black_box(walker));
        let _ = p.plan(&clock, point());
        let _ = p.update_obstacle(black_box(ObstacleId(7)), walker);
        let _ = p.grow(&clock);
    }
    // Live cell edits: marked and cleared, planned against, read.
    let cell = |v: u16| black_box(v);
    let _ = p.set_cells((cell(3), cell(0)), (cell(3), cell(19)), black_box(true));
    let _ = p.plan(&clock, point());
    let _ = p.set_cells((cell(3), cell(5)), (cell(70), cell(6)), black_box(false));
    let _ = p.grow(&clock);
    let live = p.map().live();
    let _ = black_box(live.is_occupied(cell(3), cell(4)) ^ live.segment_free(point(), point()));
    let _ = black_box(p.map().in_wall(point()) ^ live.point_free(point()));
    let _ = black_box(p.map().body_clear(point(), point()) ^ p.map().check_point(point()).is_ok());
    let _ = run_to_goal(
        &mut p,
        &clock,
        point(),
        &black_box(Protocol::default()),
        |_, _, _| {},
    );
    p.clear_goal();
    black_box(p.tree().len() as u32) ^ black_box(p.stats().expansions as u32)
}

#[entry]
fn main() -> ! {
    // Grid and its queries.
    let mut bits = [0u8; 64];
    let _ = pack_grid(&mut bits, black_box(20), black_box(20), |c, r| c == r);
    let grid = OccupancyGrid::new(
        black_box(&bits),
        black_box(20),
        black_box(20),
        black_box(1.0),
    );
    let mut sink = 0u32;
    if let Ok(g) = grid {
        sink ^= g.segment_free(point(), point()) as u32;
        sink ^= g.cell_of(point()).map_or(0, |(c, _)| c as u32);
        // Tables: written, read back, and read from opaque bytes.
        let header = black_box(TableHeader {
            map_hash: None,
            kind: ElementKind::I16,
            dims: 2,
            cols: 20,
            rows: 20,
            cell_size: 1.0,
            scale: 0.01,
            layout: bi_am_rrt::metric::Layout::Uniform,
        });
        let mut table = [0u8; 32 + 20 * 20 * 2 * 2];
        let _ = write_table(&header, &mut table, |c, r, out| {
            for (i, o) in out.iter_mut().enumerate() {
                *o = (c as f32 + r as f32) * i as f32;
            }
            true
        });
        let mut storage = Storage::<32, 8>::new();
        let mut overlay = [0u8; 64];
        let mut space = [0u8; 64];
        let mut field = [0u8; 512];
        // A grid inflated on its own, and declared baked.
        let mut inflated = [0u8; 64];
        if let Ok(i) = bi_am_rrt::map::inflate(&g, black_box(0.7), black_box(&mut inflated[..])) {
            sink ^= i.is_occupied(black_box(3), black_box(4)) as u32;
            if let Ok(m) = Map::<'_, 2>::new(g).with_baked_body(i) {
                sink ^= m.free_point(point()) as u32;
            }
        }
        sink ^= g
            .inflated_for(black_box(0.2))
            .map_or(0, |i| i.inflation().to_bits());
        if let Ok(t) = DiffusionTable::new(black_box(&table[..])) {
            let mut coords = [0f32; 4];
            sink ^= t.coordinates(point(), &mut coords) as u32;
            sink ^= t.distance(point(), point()).to_bits();
            sink ^= exercise_planner(
                &mut storage,
                g,
                black_box(&mut overlay[..]),
                black_box(&mut space[..]),
                black_box(&mut field[..]),
                t,
            );
        }
        if let Ok(t) = DiffusionTable::new_unverified(black_box(&table[..])) {
            sink ^= t.distance(point(), point()).to_bits();
        }
        sink ^= exercise_planner(
            &mut storage,
            g,
            black_box(&mut overlay[..]),
            black_box(&mut space[..]),
            black_box(&mut field[..]),
            Euclidean,
        );
    }
    // Tree and index on their own.
    let mut tree: Tree<16> = Tree::new();
    let root = tree.reset(point());
    if let Ok(a) = tree.add(point(), root, black_box(false)) {
        let _ = tree.set_parent(black_box(NodeId(black_box(3))), a, false);
        let _ = tree.set_root(black_box(NodeId(black_box(1))));
        let _ = tree.remove_leaf(black_box(NodeId(black_box(2))));
        let mut path = [NodeId(0); 4];
        let _ = black_box(tree.path_ids(a, &mut path));
        sink ^= tree.validate().is_ok() as u32;
    }
    if let Some(mut idx) =
        SpatialIndex::<16, 4>::with_bounds(black_box(10.0), black_box(1e20), black_box(0.5))
    {
        let pts = [point(); 16];
        let _ = idx.insert(NodeId(black_box(3)), point());
        sink ^= idx.nearest(point(), &pts).map_or(0, |(id, _)| id.0 as u32);
        let mut out = heapless::Vec::<NodeId, 8>::new();
        sink ^= idx.within(point(), black_box(3.0), &pts, &mut out) as u32;
        let _ = idx.remove(NodeId(black_box(3)), point());
    }
    // Clocks.
    let clock = FakeClock::new(black_box(u64::MAX));
    let d = Deadline::after(&clock, black_box(Duration::MAX));
    sink ^= d.expired(&clock) as u32;
    sink ^= clock.duration(black_box(u64::MAX)).subsec_nanos();
    // The Cortex-M clocks, on the real peripherals.
    if let Some(mut cp) = cortex_m::Peripherals::take() {
        let dwt = bi_am_rrt::cortex::DwtClock::start(&mut cp.DCB, &mut cp.DWT, black_box(0));
        sink ^= dwt.now() as u32 ^ dwt.ticks(black_box(Duration::MAX)) as u32;
        let st = bi_am_rrt::cortex::SysTickClock::start(cp.SYST, black_box(168_000_000));
        sink ^= st.now() as u32;
        bi_am_rrt::cortex::on_systick_wrap();
    }
    black_box(sink);
    loop {
        black_box(());
    }
}
