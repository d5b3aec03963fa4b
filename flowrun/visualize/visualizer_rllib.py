"""Flow compatibility: re-exports. Flow's ``flow.visualize.visualizer_rllib`` path.

The functions live in :mod:`flowrun.training.rllib.visualizer`; as a script
(``python -m flowrun.visualize.visualizer_rllib RUN_DIR CHECKPOINT``) it replays a checkpoint.
"""

from flowrun.training.rllib.visualizer import create_parser, visualizer_rllib

__all__ = ["create_parser", "visualizer_rllib"]

if __name__ == "__main__":
    import sys

    from flowrun.errors import FlowrunError

    try:
        visualizer_rllib(create_parser().parse_args())
    except FlowrunError as e:
        sys.exit(f"visualizer_rllib: error: {e}")
