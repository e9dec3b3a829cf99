"""The rendering example and the rendering benchmark of docs/rendering.md."""
