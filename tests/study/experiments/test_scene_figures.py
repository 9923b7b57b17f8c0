"""Scene panels: the robot's start drawn where the scene says, the landscape labelled cell by cell."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from crfmap.errors import InputError  # noqa: E402
from crfstudy.experiments.scene_figures import draw, landscape_figure  # noqa: E402
from crfmap.world.scenes import occluded_walls  # noqa: E402


def test_draw_marks_the_start_only_with_a_scene():
    scene = occluded_walls("train", size=20)
    fig, (a, b) = plt.subplots(1, 2)
    draw(a, scene.truth, "with", scene)
    draw(b, scene.truth, "without")
    ((x,), (y,)) = a.lines[0].get_data()
    assert (x, y) == tuple(scene.start[:2]) and not b.lines and a.get_title() == "with"
    plt.close(fig)


def test_landscape_labels_each_cell_and_refuses_a_wrong_shape():
    landscape = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    fig = landscape_figure(landscape, (1.0, 10.0), (0.5, 1.0, 2.0), "title")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.texts] == ["0.100", "0.200", "0.300", "0.400", "0.500", "0.600"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["1.0", "10.0"]
    plt.close(fig)
    with pytest.raises(InputError, match="landscape"):
        landscape_figure(landscape.T, (1.0, 10.0), (0.5, 1.0, 2.0), "title")
