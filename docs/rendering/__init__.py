"""The rendering example of docs/rendering.md and the rendering benchmark of docs/evidence-rendering.md."""
