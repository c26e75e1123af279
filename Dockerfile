# handbench explorer image: `docker build -t handbench . && docker run -p 8080:8080 handbench`
# (not built in this project's CI: its machines have no Docker engine).
FROM python:3.11-slim

# chromium: for `handbench screenshot` and the browser tests; libgl/libglib: trimesh/matplotlib
RUN apt-get update \
    && apt-get install -y --no-install-recommends chromium libgl1 libglib2.0-0 \
    && rm -rf /var/lib/apt/lists/*

WORKDIR /opt/handbench
COPY pyproject.toml README.md ./
COPY app ./app
COPY hand_models ./hand_models
COPY objects ./objects
COPY static ./static
# editable install: the data folders (hand_models/, objects/) are read next to app/
RUN pip install --no-cache-dir -e .
# compile the compiled engine's numba kernels into their on-disk cache (about a minute), so
# that the first live score does not pay it
RUN python -m app.sim.warm

ENV HANDBENCH_STORE=/data/results.sqlite
VOLUME ["/data"]
EXPOSE 8080
CMD ["handbench", "serve", "--host", "0.0.0.0", "--port", "8080"]
