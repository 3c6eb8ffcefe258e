"""Files: everything that writes to the disk, and the YAML reader.

* :mod:`~ftc_mc.io.atomic`: atomic writes (a temporary file renamed when
  complete) with the umask's file mode;
* :mod:`~ftc_mc.io.results`: Parquet with provenance, the output folder;
* :mod:`~ftc_mc.io.stream`: a Parquet file written row group by row group;
* :mod:`~ftc_mc.io.chunks`: the chunk store of resumable runs;
* :mod:`~ftc_mc.io.lock`: the output-folder and compile locks;
* :mod:`~ftc_mc.io.yamlfile`: safe YAML reading.

The on-disk cache of offline designs is :mod:`ftc_mc.cache`'s.
"""
