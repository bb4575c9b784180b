"""MediaPipe's Holistic solution imported without its drawing helpers (`bsv.frontend.mediapipe_loader`):
matplotlib.pyplot is not imported with it, and a caller who reads the drawing helpers gets the real modules.
Each case runs in a fresh interpreter (the import is once per process)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("mediapipe", reason="mediapipe not installed (pip install -r requirements-frontend.txt)")


def _run(code: str) -> str:
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def test_holistic_imports_without_pyplot_and_the_drawing_helpers_still_work() -> None:
    out = _run("""
        import sys
        from bsv.frontend.mediapipe_loader import holistic
        h = holistic()
        assert hasattr(h, "Holistic")
        print("pyplot after import:", "matplotlib.pyplot" in sys.modules)
        import mediapipe as mp
        du = mp.solutions.drawing_utils
        spec = du.DrawingSpec(color=(1, 2, 3))
        assert spec.color == (1, 2, 3)
        style = mp.solutions.drawing_styles.get_default_pose_landmarks_style()
        assert len(style) == 33
        real = sys.modules["mediapipe.python.solutions.drawing_utils"]
        assert not getattr(real, "__bsv_deferred__", False) and hasattr(real, "draw_landmarks")
        assert mp.solutions.drawing_utils is real
        print("pyplot after use:", "matplotlib.pyplot" in sys.modules)
    """)
    assert "pyplot after import: False" in out
    assert "pyplot after use: True" in out


def test_the_tasks_api_is_deferred_and_imports_as_usual_afterwards() -> None:
    out = _run("""
        import sys
        from bsv.frontend.mediapipe_loader import holistic
        holistic()
        print("audio after import:", "mediapipe.tasks.python.audio" in sys.modules)
        import importlib
        vision_direct = importlib.import_module("mediapipe.tasks.python.vision")  # (`import ... as` fails in
        # plain MediaPipe too: its __init__ binds mediapipe.tasks to the Tasks package)
        from mediapipe.tasks.python import vision as vision_from
        import mediapipe as mp
        assert vision_direct is vision_from is sys.modules["mediapipe.tasks.python.vision"]
        assert mp.tasks.vision is vision_direct  # MediaPipe's own spelling, once the package is loaded
        assert mp.tasks.BaseOptions is sys.modules["mediapipe.tasks.python.core.base_options"].BaseOptions
        options = mp.tasks.vision.PoseLandmarkerOptions(base_options=mp.tasks.BaseOptions(model_asset_path="x"))
        assert options.base_options.model_asset_path == "x"
        real = sys.modules["mediapipe.tasks.python"]
        assert not getattr(real, "__bsv_deferred__", False) and real.vision is vision_direct
        print("audio after use:", "mediapipe.tasks.python.audio" in sys.modules)
    """)
    assert "audio after import: False" in out
    assert "audio after use: True" in out


def test_mediapipe_imported_before_is_left_as_it_is() -> None:
    out = _run("""
        import sys
        import mediapipe
        from bsv.frontend.mediapipe_loader import holistic
        holistic()
        mod = sys.modules["mediapipe.python.solutions.drawing_utils"]
        print("stand-in:", getattr(mod, "__bsv_deferred__", False))
    """)
    assert "stand-in: False" in out


def test_the_segmentation_imports_mediapipe_without_pyplot() -> None:
    out = _run("""
        import sys
        from bsv.frontend import segment
        segment._mediapipe_holistic()
        print("pyplot:", "matplotlib.pyplot" in sys.modules)
    """)
    assert "pyplot: False" in out
