#!/usr/bin/env python3
"""Static checks of pdsm's deployment files (no Docker, kubectl or Slurm needed).

    python3 tests/deploy/check_manifests.py [DEPLOY_DIR]     (default: <repo>/deploy)

Checks:
  * docker-compose.yml parses; services "coordinator" and "worker" exist; their secrets,
    volumes and depends_on refer to things that are declared; secret files are the ones
    deploy/make_secrets.sh generates (or exist); build targets are stages of the Dockerfile.
    Override files docker-compose.*.yml parse and only extend services of the base file;
    their secret files lie in deploy/secrets/.
  * every YAML file in k8s/ parses (multi-document); each document has apiVersion, kind and
    metadata.name; kustomization.yaml lists existing files and every manifest; workloads'
    selectors match their pod labels; volume mounts, Secrets, Services, probe ports and the
    HPA target refer to things that exist.
  * Kubernetes policy (issue #13's defects): no Secret among the resources (an apply would
    blank the real one); Secrets come from a secretGenerator whose files lie in a git-ignored
    folder and hold every key the pods mount; images are pinned (no `latest`, no bare name),
    the coordinator and worker tags are equal in the manifests and in `images:` and equal the
    project's VERSION; every pod sets automountServiceAccountToken: false; every emptyDir has
    a sizeLimit and every container mounting one requests and limits ephemeral-storage of at
    least their sum; listen addresses are not IPv4-only; a Deployment an HPA scales sets no
    replicas; the HPA scales on a metric besides CPU; the workers have a PodDisruptionBudget
    and topology spread; a NetworkPolicy selects each workload's pods.
  * Dockerfile.dockerignore exists, excludes deploy/secrets/ and no COPY source.
  * the Dockerfile splits into instructions that are all valid keywords; it starts with
    ARG/FROM; stage names are unique; FROM <stage> and COPY --from=<stage> refer to earlier
    stages; the targets "coordinator", "worker" and "runtime" exist; JSON-form CMD,
    ENTRYPOINT, SHELL and HEALTHCHECK CMD are valid JSON string arrays; COPY sources exist.
  * `bash -n` on every .sh and .sbatch file under the deploy directory.
  * systemd units have [Unit], [Service] with an absolute ExecStart=, only key=value lines.

Prints every problem found and exits 1 if there was any (2 on bad usage).
"""

import fnmatch
import glob
import json
import os
import re
import shlex
import subprocess
import sys

try:
    import yaml
except ImportError:  # pragma: no cover - environment problem, not a manifest problem
    print("check_manifests: PyYAML is missing (apt-get install python3-yaml)", file=sys.stderr)
    sys.exit(1)


def parse_quantity(text):
    """A Kubernetes quantity ("10Gi", "512M", "1") in bytes (units as in resource.Quantity)."""
    m = re.fullmatch(r"([0-9.]+)([KMGTPE]i?|k|m)?", str(text).strip())
    if not m:
        return 0
    scale = {None: 1, "m": 1e-3, "k": 1e3, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12, "P": 1e15,
             "E": 1e18, "Ki": 2**10, "Mi": 2**20, "Gi": 2**30, "Ti": 2**40, "Pi": 2**50,
             "Ei": 2**60}[m.group(2)]
    return float(m.group(1)) * scale


class Checker:
    def __init__(self, deploy_dir):
        self.deploy = os.path.abspath(deploy_dir)
        self.repo = os.path.dirname(self.deploy)  # Docker build context: the repository root
        self.problems = []
        self.checked = []

    def problem(self, where, message):
        self.problems.append(f"{self.rel(where)}: {message}")

    def rel(self, path):
        return os.path.relpath(path, self.repo) if os.path.isabs(path) else path

    def load_yaml(self, path):
        """All documents of a YAML file (empty ones dropped), or None after reporting."""
        try:
            with open(path, encoding="utf-8") as f:
                return [d for d in yaml.safe_load_all(f) if d is not None]
        except (OSError, yaml.YAMLError) as e:
            self.problem(path, f"does not parse as YAML: {e}")
            return None

    # ------------------------------------------------------------------------------ Dockerfile

    INSTRUCTIONS = {
        "ADD", "ARG", "CMD", "COPY", "ENTRYPOINT", "ENV", "EXPOSE", "FROM", "HEALTHCHECK",
        "LABEL", "MAINTAINER", "ONBUILD", "RUN", "SHELL", "STOPSIGNAL", "USER", "VOLUME",
        "WORKDIR",
    }

    def parse_dockerfile(self, path):
        """[(line number, KEYWORD, arguments)] following Docker's rules: parser directives
        at the top, `#` comment lines (also inside continuations), line continuation with the
        escape character at the end of a line."""
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        escape = "\\"
        i = 0
        # Parser directives: "# key=value" lines before anything else.
        while i < len(lines):
            m = re.match(r"^#\s*([a-zA-Z]+)\s*=\s*(\S+)\s*$", lines[i])
            if not m:
                break
            if m.group(1).lower() == "escape":
                escape = m.group(2)
            i += 1
        instructions = []
        current, start = None, 0
        for n in range(i, len(lines)):
            line = lines[n]
            stripped = line.strip()
            if current is None:
                if not stripped or stripped.startswith("#"):
                    continue
                current, start = "", n + 1
            elif stripped.startswith("#") or not stripped:
                continue  # comments and empty lines inside a continuation are dropped
            text = line.rstrip()
            if text.endswith(escape):
                current += text[: -len(escape)] + " "
                continue
            current += text
            keyword, _, args = current.strip().partition(" ")
            instructions.append((start, keyword, args.strip()))
            current = None
        if current is not None:
            self.problem(path, f"line {start}: the last instruction ends with a line continuation")
        return instructions

    def check_json_array(self, path, lineno, keyword, text):
        if not text.startswith("["):
            return  # shell form
        try:
            value = json.loads(text)
        except json.JSONDecodeError as e:
            self.problem(path, f"line {lineno}: {keyword} looks like exec form but is not JSON: {e}")
            return
        if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
            self.problem(path, f"line {lineno}: {keyword} exec form must be a non-empty array of strings")

    def check_dockerfile(self, path):
        """Returns the set of stage names (for the compose check)."""
        self.checked.append(self.rel(path))
        if not os.path.isfile(path):
            self.problem(path, "missing")
            return set()
        instructions = self.parse_dockerfile(path)
        if not instructions:
            self.problem(path, "no instructions")
            return set()
        stages = []  # names (lower case) or None, in order
        seen_from = False
        for lineno, keyword, args in instructions:
            kw = keyword.upper()
            if kw not in self.INSTRUCTIONS:
                self.problem(path, f"line {lineno}: unknown instruction {keyword!r}")
                continue
            if not seen_from and kw not in ("ARG", "FROM"):
                self.problem(path, f"line {lineno}: {kw} before the first FROM")
            if not args and kw not in ("ONBUILD",):
                self.problem(path, f"line {lineno}: {kw} without arguments")
            if kw == "FROM":
                seen_from = True
                words = [w for w in args.split() if not w.startswith("--")]
                if len(words) == 3 and words[1].upper() == "AS":
                    name = words[2].lower()
                    if not re.fullmatch(r"[a-z][a-z0-9_.-]*", name):
                        self.problem(path, f"line {lineno}: invalid stage name {words[2]!r}")
                    if name in stages:
                        self.problem(path, f"line {lineno}: stage {name!r} defined twice")
                    stages.append(name)
                elif len(words) == 1:
                    stages.append(None)
                else:
                    self.problem(path, f"line {lineno}: FROM wants 'IMAGE [AS NAME]', got {args!r}")
                    stages.append(None)
            elif kw in ("COPY", "ADD"):
                self.check_copy(path, lineno, kw, args, stages)
            elif kw in ("CMD", "ENTRYPOINT", "SHELL"):
                self.check_json_array(path, lineno, kw, args)
                if kw == "SHELL" and not args.startswith("["):
                    self.problem(path, f"line {lineno}: SHELL must use the JSON form")
            elif kw == "HEALTHCHECK":
                m = re.fullmatch(r"((?:--\S+\s+)*)(CMD|NONE)\b\s*(.*)", args, re.I | re.S)
                if not m:
                    self.problem(path, f"line {lineno}: HEALTHCHECK wants [OPTIONS] CMD ... or NONE")
                    continue
                for option in m.group(1).split():
                    if not re.fullmatch(r"--(interval|timeout|start-period|start-interval|retries)=\S+", option):
                        self.problem(path, f"line {lineno}: unknown HEALTHCHECK option {option!r}")
                if m.group(2).upper() == "CMD":
                    if not m.group(3):
                        self.problem(path, f"line {lineno}: HEALTHCHECK CMD without a command")
                    self.check_json_array(path, lineno, "HEALTHCHECK CMD", m.group(3))
        # FROM <name>: a stage defined before this one, or an image with a tag or registry.
        index = 0
        for lineno, keyword, args in instructions:
            if keyword.upper() != "FROM":
                continue
            image = next((w for w in args.split() if not w.startswith("--")), "").lower()
            if image in stages:
                if stages.index(image) >= index:
                    self.problem(path, f"line {lineno}: FROM {image!r} refers to a later stage")
            elif image != "scratch" and not any(c in image for c in ":/@$"):
                self.problem(path, f"line {lineno}: FROM {image!r} is neither an earlier stage "
                                   "nor a tagged image (typo in a stage name?)")
            index += 1
        names = {s for s in stages if s}
        for target in ("runtime", "coordinator", "worker"):
            if target not in names:
                self.problem(path, f"target stage {target!r} is missing (stages: {sorted(names)})")
        return names

    def check_copy(self, path, lineno, kw, args, stages):
        try:
            words = shlex.split(args) if not args.startswith("[") else json.loads(args)
        except (ValueError, json.JSONDecodeError) as e:
            self.problem(path, f"line {lineno}: cannot split {kw} arguments: {e}")
            return
        options = [w for w in words if w.startswith("--")]
        paths = [w for w in words if not w.startswith("--")]
        if len(paths) < 2:
            self.problem(path, f"line {lineno}: {kw} wants at least a source and a destination")
            return
        source_stage = None
        for option in options:
            name, _, value = option[2:].partition("=")
            if name not in ("from", "chown", "chmod", "link", "parents", "exclude", "checksum",
                            "keep-git-dir"):
                self.problem(path, f"line {lineno}: unknown {kw} option {option!r}")
            if name == "from":
                source_stage = value.lower()
                if value.isdigit():
                    if int(value) >= len(stages):
                        self.problem(path, f"line {lineno}: --from={value}: no such earlier stage")
                elif source_stage not in stages and ":" not in value and "/" not in value:
                    self.problem(path, f"line {lineno}: --from={value}: "
                                       "no stage of that name before this line")
            if name == "chmod" and not re.fullmatch(r"[0-7]{3,4}", value):
                self.problem(path, f"line {lineno}: --chmod={value}: not an octal mode")
        if source_stage is None:  # from the build context: the sources must exist
            for source in paths[:-1]:
                if any(c in source for c in "*?[$"):
                    continue
                if not os.path.exists(os.path.join(self.repo, source)):
                    self.problem(path, f"line {lineno}: {kw} source {source!r} is not in the build context")
                pattern = self.ignored(source)
                if pattern:
                    self.problem(path, f"line {lineno}: {kw} source {source!r} is excluded by "
                                       f"Dockerfile.dockerignore pattern {pattern!r}")

    def dockerignore_patterns(self):
        try:
            with open(os.path.join(self.deploy, "Dockerfile.dockerignore"), encoding="utf-8") as f:
                return [l.strip() for l in f if l.strip() and not l.lstrip().startswith("#")]
        except OSError:
            return []

    def ignored(self, source):
        """The last .dockerignore pattern excluding `source` (prefix/glob match; "!" re-includes)."""
        source = os.path.normpath(source)
        if source == ".":
            return None
        result = None
        for pattern in self.dockerignore_patterns():
            negate = pattern.startswith("!")
            bare = os.path.normpath(pattern.lstrip("!").lstrip("/"))
            parts = source.split(os.sep)
            prefixes = [os.sep.join(parts[:i]) for i in range(1, len(parts) + 1)]
            globbed = bare.replace("**/", "")
            if any(fnmatch.fnmatchcase(p, bare) or fnmatch.fnmatchcase(os.path.basename(p), globbed)
                   and bare.startswith("**/") for p in prefixes):
                result = None if negate else pattern
        return result

    def check_dockerignore(self):
        path = os.path.join(self.deploy, "Dockerfile.dockerignore")
        if not os.path.isfile(path):
            self.problem(path, "missing: the whole repository, secrets included, would be sent to the builder")
            return
        self.checked.append(self.rel(path))
        if not self.ignored("deploy/secrets/client_token"):
            self.problem(path, "does not exclude deploy/secrets/")

    # --------------------------------------------------------------------------------- compose

    def check_compose(self, path, stages, base=None):
        """docker-compose.yml, or with `base` (its parsed mapping) an override file such as
        docker-compose.tls.yml that only adds to services the base defines. Returns the mapping."""
        self.checked.append(self.rel(path))
        if not os.path.isfile(path):
            self.problem(path, "missing")
            return
        docs = self.load_yaml(path)
        if not docs:
            if docs is not None:
                self.problem(path, "empty")
            return
        if len(docs) != 1 or not isinstance(docs[0], dict):
            self.problem(path, "expected one YAML mapping")
            return
        compose = docs[0]
        services = compose.get("services")
        if not isinstance(services, dict) or not services:
            self.problem(path, "no services")
            return
        base_services = (base or {}).get("services") or {}
        for required in ("coordinator", "worker"):
            if base is None and required not in services:
                self.problem(path, f"service {required!r} is missing")
        for name in services:
            if base is not None and name not in base_services:
                self.problem(path, f"overrides service {name!r}, which the base compose file does not define")
        secrets = dict((base or {}).get("secrets") or {})
        secrets.update(compose.get("secrets") or {})
        volumes = dict((base or {}).get("volumes") or {})
        volumes.update(compose.get("volumes") or {})
        secrets_dir = os.path.join(self.deploy, "secrets")
        generated = self.generated_secret_names()
        for name, secret in (compose.get("secrets") or {}).items():
            if not isinstance(secret, dict) or not ("file" in secret or "environment" in secret
                                                   or "external" in secret):
                self.problem(path, f"secret {name!r} needs file:, environment: or external:")
                continue
            if "file" in secret:
                file = os.path.normpath(os.path.join(os.path.dirname(path), secret["file"]))
                if os.path.dirname(file) != secrets_dir:
                    self.problem(path, f"secret {name!r}: {secret['file']} is outside deploy/secrets/ "
                                       "(the folder git ignores)")
                elif base is None and not (os.path.exists(file) or os.path.basename(file) in generated):
                    self.problem(path, f"secret {name!r}: {secret['file']} neither exists nor is "
                                       f"generated by make_secrets.sh ({sorted(generated)})")
        for name, service in services.items():
            where = f"{self.rel(path)} service {name!r}"
            if not isinstance(service, dict):
                self.problems.append(f"{where}: not a mapping")
                continue
            if base is None and "image" not in service and "build" not in service:
                self.problems.append(f"{where}: needs image: or build:")
            for secret in service.get("secrets") or []:
                ref = secret.get("source") if isinstance(secret, dict) else secret
                if ref not in secrets:
                    self.problems.append(f"{where}: secret {ref!r} is not declared under top-level secrets:")
            for volume in service.get("volumes") or []:
                source = volume.get("source") if isinstance(volume, dict) else str(volume).split(":")[0]
                if source and not source.startswith((".", "/", "~", "$")) and source not in volumes:
                    self.problems.append(f"{where}: named volume {source!r} is not declared under volumes:")
            depends = service.get("depends_on") or []
            for dep in (depends.keys() if isinstance(depends, dict) else depends):
                if dep not in services and dep not in base_services:
                    self.problems.append(f"{where}: depends_on {dep!r}, which is no service")
            build = service.get("build")
            if isinstance(build, dict):
                context = os.path.normpath(os.path.join(os.path.dirname(path), build.get("context", ".")))
                dockerfile = os.path.join(context, build.get("dockerfile", "Dockerfile"))
                if not os.path.isfile(dockerfile):
                    self.problems.append(f"{where}: build dockerfile {self.rel(dockerfile)} does not exist")
                target = build.get("target")
                ours = os.path.realpath(os.path.join(self.deploy, "Dockerfile"))
                if target and os.path.realpath(dockerfile) == ours \
                        and target.lower() not in stages:
                    self.problems.append(f"{where}: build target {target!r} is no stage of the Dockerfile")
            command = service.get("command")
            if command is not None and not isinstance(command, (str, list)):
                self.problems.append(f"{where}: command must be a string or a list")
        return compose

    def generated_secret_names(self):
        """The file names deploy/make_secrets.sh writes (its `for name in ...` loop)."""
        script = os.path.join(self.deploy, "make_secrets.sh")
        try:
            with open(script, encoding="utf-8") as f:
                m = re.search(r"^\s*for name in ([^;]+);", f.read(), re.M)
        except OSError:
            return set()
        return set(m.group(1).split()) if m else set()

    # ------------------------------------------------------------------------------ Kubernetes

    def check_k8s(self, k8s_dir):
        files = sorted(glob.glob(os.path.join(k8s_dir, "*.yaml")) + glob.glob(os.path.join(k8s_dir, "*.yml")))
        if not files:
            self.problem(k8s_dir, "no manifests")
            return
        objects = []  # (file, doc)
        kustomization = None
        for file in files:
            self.checked.append(self.rel(file))
            docs = self.load_yaml(file)
            if docs is None:
                continue
            if not docs:
                self.problem(file, "no documents")
            for i, doc in enumerate(docs):
                where = f"{self.rel(file)} document {i + 1}"
                if not isinstance(doc, dict):
                    self.problems.append(f"{where}: not a mapping")
                    continue
                if doc.get("kind") == "Kustomization":
                    kustomization = (file, doc)
                    if not str(doc.get("apiVersion", "")).startswith("kustomize.config.k8s.io/"):
                        self.problems.append(f"{where}: Kustomization needs apiVersion kustomize.config.k8s.io/...")
                    continue
                for key in ("apiVersion", "kind"):
                    if not doc.get(key):
                        self.problems.append(f"{where}: missing {key}")
                if not isinstance(doc.get("metadata"), dict) or not doc["metadata"].get("name"):
                    self.problems.append(f"{where}: missing metadata.name")
                    continue
                if "namespace" in doc["metadata"]:
                    self.problems.append(f"{where}: sets metadata.namespace (manifests must be namespace-agnostic)")
                objects.append((file, doc))
        generated_secrets = {}
        if kustomization is None:
            self.problem(k8s_dir, "no kustomization.yaml")
        else:
            self.check_kustomization(*kustomization, files)
            generated_secrets = self.check_secret_generator(*kustomization)
        self.check_k8s_references(objects, generated_secrets)
        self.check_k8s_policy(objects, kustomization, generated_secrets)

    def check_secret_generator(self, file, doc):
        """{secret name: set of keys} of the kustomization's secretGenerator, after checking
        that each file lies in a folder whose .gitignore ignores everything."""
        generated = {}
        base = os.path.dirname(file)
        for generator in doc.get("secretGenerator") or []:
            name = generator.get("name")
            keys = set()
            for entry in generator.get("files") or []:
                key, _, source = str(entry).partition("=")
                if not source:
                    key, source = os.path.basename(key), key
                keys.add(key)
                folder = os.path.dirname(os.path.normpath(os.path.join(base, source)))
                if not self.ignores_everything(os.path.join(folder, ".gitignore")):
                    self.problem(file, f"secretGenerator {name!r}: {source} is not in a folder whose "
                                       ".gitignore ignores everything (tokens could be committed)")
            if generator.get("literals") or generator.get("envs"):
                self.problem(file, f"secretGenerator {name!r}: literals/envs would keep secrets in "
                                   "the repository; use files:")
            generated[name] = keys
        return generated

    @staticmethod
    def ignores_everything(gitignore):
        try:
            with open(gitignore, encoding="utf-8") as f:
                lines = [l.strip() for l in f if l.strip() and not l.startswith("#")]
        except OSError:
            return False
        return "*" in lines

    def project_version(self):
        try:
            with open(os.path.join(self.repo, "CMakeLists.txt"), encoding="utf-8") as f:
                m = re.search(r"project\(\s*pdsm\s+VERSION\s+([0-9.]+)", f.read())
        except OSError:
            return None
        return m.group(1) if m else None

    def check_k8s_policy(self, objects, kustomization, generated_secrets):
        by_kind = {}
        for file, doc in objects:
            by_kind.setdefault(doc["kind"], {})[doc["metadata"]["name"]] = (file, doc)
        for name, (file, _) in by_kind.get("Secret", {}).items():
            self.problems.append(f"{self.rel(file)} Secret {name}: a Secret among the resources "
                                 "overwrites the real one on every apply; use secretGenerator "
                                 "or an out-of-band Secret")
        version = self.project_version()
        tags = {}  # image name -> set of tags seen (manifests and kustomization images:)
        if kustomization is not None:
            for image in kustomization[1].get("images") or []:
                tag = str(image.get("newTag", ""))
                if not tag or tag == "latest":
                    self.problem(kustomization[0], f"images: {image.get('name')!r} needs a pinned newTag")
                tags.setdefault(image.get("name"), set()).add(tag)
        scaled = {((doc.get("spec") or {}).get("scaleTargetRef") or {}).get("name")
                  for _, doc in by_kind.get("HorizontalPodAutoscaler", {}).values()}
        policies = [doc for _, doc in by_kind.get("NetworkPolicy", {}).values()]
        budgets = [doc for _, doc in by_kind.get("PodDisruptionBudget", {}).values()]

        def selects(selector, labels):
            match = (selector or {}).get("matchLabels") or {}
            return bool(match) and all(labels.get(k) == v for k, v in match.items())

        for kind in ("Deployment", "StatefulSet"):
            for name, (file, doc) in by_kind.get(kind, {}).items():
                where = f"{self.rel(file)} {kind} {name}"
                spec = doc.get("spec") or {}
                template = spec.get("template") or {}
                labels = (template.get("metadata") or {}).get("labels") or {}
                pod = template.get("spec") or {}
                if pod.get("automountServiceAccountToken") is not False:
                    self.problems.append(f"{where}: set automountServiceAccountToken: false "
                                         "(pdsm never calls the Kubernetes API)")
                if name in scaled and "replicas" in spec:
                    self.problems.append(f"{where}: sets replicas although an HPA scales it "
                                         "(every apply would reset the HPA's count)")
                if not any(selects(p.get("spec", {}).get("podSelector"), labels) for p in policies):
                    self.problems.append(f"{where}: no NetworkPolicy selects its pods")
                if labels.get("app.kubernetes.io/component") == "worker":
                    if not any(selects((b.get("spec") or {}).get("selector"), labels) for b in budgets):
                        self.problems.append(f"{where}: no PodDisruptionBudget selects its pods")
                    if not pod.get("topologySpreadConstraints"):
                        self.problems.append(f"{where}: no topologySpreadConstraints")
                empty_dirs = {}
                for volume in pod.get("volumes") or []:
                    if "emptyDir" in volume:
                        limit = (volume.get("emptyDir") or {}).get("sizeLimit")
                        if not limit:
                            self.problems.append(f"{where}: emptyDir {volume.get('name')!r} has no sizeLimit")
                        empty_dirs[volume.get("name")] = parse_quantity(limit or "0")
                    secret = volume.get("secret") or {}
                    wanted = {i.get("key") for i in secret.get("items") or []}
                    have = generated_secrets.get(secret.get("secretName"))
                    if have is not None and not wanted <= have:
                        self.problems.append(f"{where}: volume {volume.get('name')!r} wants keys "
                                             f"{sorted(wanted - have)} the secretGenerator lacks")
                for container in pod.get("containers") or []:
                    cwhere = f"{where} container {container.get('name')!r}"
                    image = str(container.get("image", ""))
                    image_name, _, tag = image.rpartition(":") if ":" in image.split("/")[-1] else (image, "", "")
                    if not tag or tag == "latest":
                        self.problems.append(f"{cwhere}: image {image!r} is not pinned to a release tag")
                    tags.setdefault(image_name.split("/")[-1], set()).add(tag)
                    args = [str(a) for a in container.get("args") or []]
                    for flag, value in zip(args, args[1:]):
                        if flag.endswith("listen") and value.startswith("0.0.0.0"):
                            self.problems.append(f"{cwhere}: {flag} {value} is IPv4 only; use [::]")
                    mounted = sum(empty_dirs.get(m.get("name"), 0)
                                  for m in container.get("volumeMounts") or [])
                    resources = container.get("resources") or {}
                    for side in ("requests", "limits"):
                        amount = (resources.get(side) or {}).get("ephemeral-storage")
                        if mounted and amount is None:
                            self.problems.append(f"{cwhere}: mounts emptyDirs but has no "
                                                 f"resources.{side}.ephemeral-storage")
                        elif mounted and parse_quantity(amount) < mounted:
                            self.problems.append(f"{cwhere}: resources.{side}.ephemeral-storage "
                                                 f"{amount} is below its emptyDirs' sizeLimits")
        pdsm_tags = {tuple(sorted(tags.get(n, set()))) for n in ("pdsm-coordinator", "pdsm-worker")}
        all_tags = set().union(*(tags.get(n, set()) for n in ("pdsm-coordinator", "pdsm-worker")))
        if len(all_tags) > 1 or len(pdsm_tags) > 1:
            self.problems.append(f"k8s: coordinator and worker images must carry one release tag, "
                                 f"found {sorted(all_tags)}")
        if version and all_tags and all_tags != {version}:
            self.problems.append(f"k8s: image tags {sorted(all_tags)} differ from the project "
                                 f"VERSION {version} (CMakeLists.txt)")
        for name, (file, doc) in by_kind.get("HorizontalPodAutoscaler", {}).items():
            metrics = (doc.get("spec") or {}).get("metrics") or []
            if not any(m.get("type") in ("External", "Pods", "Object") for m in metrics):
                self.problems.append(f"{self.rel(file)} HorizontalPodAutoscaler {name}: scales on "
                                     "CPU only; add the queue-depth metric")

    def check_kustomization(self, file, doc, files):
        listed = doc.get("resources") or []
        if not listed:
            self.problem(file, "lists no resources")
        base = os.path.dirname(file)
        for resource in listed:
            if not os.path.exists(os.path.join(base, resource)):
                self.problem(file, f"resource {resource!r} does not exist")
        listed_paths = {os.path.normpath(os.path.join(base, r)) for r in listed}
        for manifest in files:
            manifest = os.path.normpath(manifest)
            if manifest != os.path.normpath(file) and manifest not in listed_paths:
                self.problem(file, f"{os.path.basename(manifest)} is not listed under resources")

    def check_k8s_references(self, objects, generated_secrets):
        by_kind = {}
        for file, doc in objects:
            by_kind.setdefault(doc["kind"], {})[doc["metadata"]["name"]] = (file, doc)
        pod_labels = []  # (workload, labels) for matching Services
        for kind in ("Deployment", "StatefulSet", "DaemonSet", "Job"):
            for name, (file, doc) in by_kind.get(kind, {}).items():
                where = f"{self.rel(file)} {kind} {name}"
                spec = doc.get("spec") or {}
                template = spec.get("template") or {}
                labels = (template.get("metadata") or {}).get("labels") or {}
                selector = (spec.get("selector") or {}).get("matchLabels") or {}
                if kind != "Job":
                    if not selector:
                        self.problems.append(f"{where}: no spec.selector.matchLabels")
                    elif any(labels.get(k) != v for k, v in selector.items()):
                        self.problems.append(f"{where}: selector {selector} does not match pod labels {labels}")
                pod_labels.append((where, labels))
                pod = template.get("spec") or {}
                volumes = {v.get("name") for v in pod.get("volumes") or []}
                volumes |= {(t.get("metadata") or {}).get("name") for t in spec.get("volumeClaimTemplates") or []}
                for volume in pod.get("volumes") or []:
                    secret = (volume.get("secret") or {}).get("secretName")
                    if secret and secret not in by_kind.get("Secret", {}) \
                            and secret not in generated_secrets:
                        self.problems.append(f"{where}: volume {volume.get('name')!r} uses Secret "
                                             f"{secret!r}, which no manifest defines")
                containers = pod.get("containers") or []
                if not containers:
                    self.problems.append(f"{where}: no containers")
                for container in containers:
                    cwhere = f"{where} container {container.get('name')!r}"
                    for key in ("name", "image"):
                        if not container.get(key):
                            self.problems.append(f"{cwhere}: missing {key}")
                    for mount in container.get("volumeMounts") or []:
                        if mount.get("name") not in volumes:
                            self.problems.append(f"{cwhere}: mounts undeclared volume {mount.get('name')!r}")
                    ports = {p.get("containerPort") for p in container.get("ports") or []}
                    port_names = {p.get("name") for p in container.get("ports") or []}
                    for probe_name in ("startupProbe", "readinessProbe", "livenessProbe"):
                        probe = container.get(probe_name)
                        if probe is None:
                            continue
                        handlers = [h for h in ("grpc", "httpGet", "tcpSocket", "exec") if h in probe]
                        if len(handlers) != 1:
                            self.problems.append(f"{cwhere}: {probe_name} needs exactly one of grpc/httpGet/tcpSocket/exec")
                            continue
                        port = (probe[handlers[0]] or {}).get("port")
                        if handlers[0] != "exec" and port not in ports and port not in port_names:
                            self.problems.append(f"{cwhere}: {probe_name} probes port {port!r}, not a container port")
                        if handlers[0] == "grpc" and not isinstance(port, int):
                            self.problems.append(f"{cwhere}: {probe_name} grpc.port must be a number")
                    for env in container.get("env") or []:
                        ref = (env.get("valueFrom") or {}).get("resourceFieldRef")
                        if ref and ref.get("containerName") not in (None, container.get("name")):
                            self.problems.append(f"{cwhere}: env {env.get('name')} refers to another container")
        for name, (file, doc) in by_kind.get("Service", {}).items():
            where = f"{self.rel(file)} Service {name}"
            selector = (doc.get("spec") or {}).get("selector") or {}
            if selector and not any(all(labels.get(k) == v for k, v in selector.items())
                                    for _, labels in pod_labels):
                self.problems.append(f"{where}: selector {selector} matches no workload's pods")
            if not (doc.get("spec") or {}).get("ports"):
                self.problems.append(f"{where}: no ports")
        for name, (file, doc) in by_kind.get("StatefulSet", {}).items():
            service = (doc.get("spec") or {}).get("serviceName")
            found = by_kind.get("Service", {}).get(service)
            if not found:
                self.problems.append(f"{self.rel(file)} StatefulSet {name}: serviceName {service!r} is no Service here")
            elif (found[1].get("spec") or {}).get("clusterIP") != "None":
                self.problems.append(f"{self.rel(file)} StatefulSet {name}: service {service!r} is not headless")
        for name, (file, doc) in by_kind.get("HorizontalPodAutoscaler", {}).items():
            target = (doc.get("spec") or {}).get("scaleTargetRef") or {}
            if target.get("name") not in by_kind.get(target.get("kind"), {}):
                self.problems.append(f"{self.rel(file)} HorizontalPodAutoscaler {name}: target "
                                     f"{target.get('kind')}/{target.get('name')} is not defined here")

    # ------------------------------------------------------------------------- shell, systemd

    def check_shell(self):
        scripts = sorted(glob.glob(os.path.join(self.deploy, "**", "*.sh"), recursive=True)
                         + glob.glob(os.path.join(self.deploy, "**", "*.sbatch"), recursive=True))
        for script in scripts:
            self.checked.append(self.rel(script))
            result = subprocess.run(["bash", "-n", script], capture_output=True, text=True)
            if result.returncode != 0:
                self.problem(script, "bash -n failed:\n    " + result.stderr.strip().replace("\n", "\n    "))

    def check_systemd(self):
        units = sorted(glob.glob(os.path.join(self.deploy, "systemd", "*.service")))
        if not units:
            self.problem(os.path.join(self.deploy, "systemd"), "no .service units")
        for unit in units:
            self.checked.append(self.rel(unit))
            sections = {}
            section = None
            with open(unit, encoding="utf-8") as f:
                lines = f.read().split("\n")
            continued = False
            for n, line in enumerate(lines, 1):
                stripped = line.strip()
                if continued:
                    continued = stripped.endswith("\\")
                    continue
                if not stripped or stripped.startswith(("#", ";")):
                    continue
                m = re.fullmatch(r"\[([A-Za-z]+)\]", stripped)
                if m:
                    section = m.group(1)
                    sections.setdefault(section, {})
                    continue
                m = re.fullmatch(r"([A-Za-z][A-Za-z0-9]*)\s*=\s*(.*)", stripped)
                if not m:
                    self.problem(unit, f"line {n}: neither a section header nor Key=Value: {stripped!r}")
                    continue
                if section is None:
                    self.problem(unit, f"line {n}: {m.group(1)}= before any [Section]")
                    continue
                sections[section].setdefault(m.group(1), []).append(m.group(2))
                continued = stripped.endswith("\\")
            for required in ("Unit", "Service"):
                if required not in sections:
                    self.problem(unit, f"no [{required}] section")
            exec_start = (sections.get("Service") or {}).get("ExecStart") or []
            if not exec_start:
                self.problem(unit, "no ExecStart= in [Service]")
            for value in exec_start:
                if not value.lstrip("@-:+!").startswith("/"):
                    self.problem(unit, f"ExecStart={value.split()[0] if value else ''} is not an absolute path")

    def run(self):
        stages = self.check_dockerfile(os.path.join(self.deploy, "Dockerfile"))
        self.check_dockerignore()
        compose = self.check_compose(os.path.join(self.deploy, "docker-compose.yml"), stages)
        for override in sorted(glob.glob(os.path.join(self.deploy, "docker-compose.*.yml"))):
            self.check_compose(override, stages, base=compose or {})
        self.check_k8s(os.path.join(self.deploy, "k8s"))
        self.check_shell()
        self.check_systemd()
        if self.problems:
            print(f"check_manifests: {len(self.problems)} problem(s) in {self.deploy}:", file=sys.stderr)
            for p in self.problems:
                print(f"  - {p}", file=sys.stderr)
            return 1
        print(f"check_manifests: OK, {len(self.checked)} files checked:")
        for c in self.checked:
            print(f"  {c}")
        return 0


def main(argv):
    if len(argv) > 2 or (len(argv) == 2 and argv[1] in ("-h", "--help")):
        print(__doc__)
        return 2
    deploy = argv[1] if len(argv) == 2 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "..", "deploy")
    if not os.path.isdir(deploy):
        print(f"check_manifests: {deploy} is not a directory", file=sys.stderr)
        return 2
    return Checker(deploy).run()


if __name__ == "__main__":
    sys.exit(main(sys.argv))
