#!/usr/bin/python3
"""Opens a map PLY written by `rgbdtam replay --map` with Open3D (Debian: python3-open3d),
prints what it holds, and renders it to a PNG (matplotlib) so a person can look at it.

usage: tools/check_map.py map.ply [out.png] [--expect-desk]
Exit status 1 when Open3D cannot read the file or it holds no points; with --expect-desk,
also when the map's largest plane is not a desk (see desk_found).
"""
import sys

import numpy as np
import open3d as o3d


def desk_found(cloud) -> bool:
    """The largest plane (Open3D RANSAC, 1 cm) holds a quarter of the map or more, faces the
    first camera's vertical axis within 60 degrees, and lies 0.3-2 m from it: a table top."""
    (a, b, c, d), inliers = cloud.segment_plane(distance_threshold=0.01, ransac_n=3,
                                                num_iterations=1000)
    share = len(inliers) / len(cloud.points)
    print(f"  largest plane: {100 * share:.0f} % of the points, normal ({a:.2f}, {b:.2f}, {c:.2f}),"
          f" {abs(d):.2f} m from the first camera")
    return share >= 0.25 and abs(b) >= 0.5 and 0.3 <= abs(d) <= 2.0


def main() -> int:
    expect_desk = "--expect-desk" in sys.argv
    args = [a for a in sys.argv[1:] if a != "--expect-desk"]
    if not args:
        print(__doc__)
        return 2
    sys.argv[1:] = args
    cloud = o3d.io.read_point_cloud(sys.argv[1])
    points = np.asarray(cloud.points)
    if len(points) == 0:
        print(f"{sys.argv[1]}: Open3D read no points")
        return 1
    colours = np.asarray(cloud.colors)
    lo, hi = points.min(axis=0), points.max(axis=0)
    print(f"{sys.argv[1]}: {len(points)} points, colours {'yes' if len(colours) else 'no'}")
    print(f"  bounds x [{lo[0]:.2f}, {hi[0]:.2f}]  y [{lo[1]:.2f}, {hi[1]:.2f}]  z [{lo[2]:.2f}, {hi[2]:.2f}] m")
    print(f"  median distance from the first camera {np.median(np.linalg.norm(points, axis=1)):.2f} m")
    if len(sys.argv) > 2:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        # Seen from the first keyframe's camera (x right, y down, z forward), points within 4 m.
        keep = (points[:, 2] > 0.1) & (points[:, 2] < 4.0)
        p, c = points[keep], (colours[keep] if len(colours) else None)
        u, v = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
        fig, axes = plt.subplots(1, 2, figsize=(14, 6))
        axes[0].scatter(u, -v, s=0.2, c=c, marker=".")
        axes[0].set_title("seen from the first keyframe")
        axes[0].set_aspect("equal")
        axes[1].scatter(p[:, 0], -p[:, 2], s=0.2, c=c, marker=".")
        axes[1].set_title("from above (x, z)")
        axes[1].set_aspect("equal")
        for ax in axes:
            ax.set_facecolor("#3060a0")
        fig.savefig(sys.argv[2], dpi=110, bbox_inches="tight")
        print(f"  rendered {sys.argv[2]}")
    if expect_desk and not desk_found(cloud):
        print("  no desk: the largest plane is not a table top below the camera")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
