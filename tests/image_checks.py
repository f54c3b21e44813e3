"""What the renderer tests check of a written picture: a valid, non-empty image
file (and its frame count), and no temporary file left behind."""
from PIL import Image


def open_image(path):
    """(the loaded image, its number of frames) of a non-empty image file."""
    assert path.exists() and path.stat().st_size > 0
    with Image.open(path) as im:
        im.load()
        return im, getattr(im, "n_frames", 1)


def no_temp_files(directory):
    return [p.name for p in directory.iterdir() if p.name.endswith(".tmp")] == []
