"""thyrse: a branching-first inflorescence (a lilac thyrse from positional information, thesis
sec. 4.5 and ch. 7) -> florets' SCN and branch meshes. Spec: formats/thyrse.md."""
