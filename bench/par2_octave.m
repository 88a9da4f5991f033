## Octave/SLICOT side of the Par2 GU peer comparison (bench/run_peers.sh).
##
## Usage:
##   octave --no-gui --quiet --norc bench/par2_octave.m EST.csv OUT.json METHOD ORDER HORIZON REPEATS [ALG]
## METHOD is n4sid or moesp (octave-control's functions of those names, which call
## SLICOT IB01AD (R factor, SVD), IB01BD (A, B, C, D, K) and IB01CD (x0)); ALG is
## octave-control's 'alg' option: c (Cholesky, its default), f (fast QR) or q (QR).
##
## The estimation log (t,u,y) is read, the means of u and y are removed (the
## common evaluator, par2_eval.cpp, adds them back for every tool), and the
## identification call alone is timed, best of REPEATS. The model is written as
## DESIGN.md state-space JSON (Ts, A, B, C, D) with 17 significant digits.
## Prints:  RESULT tag=octave_n4sid status=ok fit_time_s=... repeats=... maxrss_mb=... base_rss_mb=...
## or, when SLICOT reports an error (exit code 3):
##          RESULT tag=octave_n4sid status=failed fit_time_s=... maxrss_mb=... reason=<SLICOT's message>
1;

function s = json_matrix (m)
  parts = cell (1, rows (m));
  for i = 1:size (m, 1)
    parts{i} = ["[", strjoin(arrayfun (@(v) sprintf ("%.17g", v), m(i,:), "uniformoutput", false), ", "), "]"];
  endfor
  s = ["[", strjoin(parts, ", "), "]"];
endfunction

args = argv ();
if (numel (args) != 6 && numel (args) != 7)
  fprintf (stderr, "usage: par2_octave.m EST.csv OUT.json n4sid|moesp ORDER HORIZON REPEATS [ALG=c|f|q]\n");
  exit (1);
endif
[est, out, method] = deal (args{1:3});
order = str2double (args{4});
horizon = str2double (args{5});
repeats = str2double (args{6});
alg = "c";                        # octave-control's default: Cholesky of the correlation matrix (IB01AD ALG='C')
if (numel (args) == 7)
  alg = args{7};
endif
tag = ["octave_", method];
if (! strcmp (alg, "c"))
  tag = [tag, "_alg_", alg];
endif

pkg load control
raw = dlmread (est, ",", 1, 0);   # header row skipped; columns t, u, y
t = raw(:, 1); u = raw(:, 2); y = raw(:, 3);
Ts = (t(end) - t(1)) / (numel (t) - 1);
u = u - mean (u);
y = y - mean (y);
dat = iddata (y, u, Ts);
r0 = getrusage ();

switch (method)
  case "n4sid"
    ident = @n4sid;
  case "moesp"
    ident = @moesp;
  otherwise
    fprintf (stderr, "par2_octave.m: unknown method '%s'\n", method);
    exit (1);
endswitch

best = Inf;
for k = 1:repeats
  t0 = tic ();
  try
    [sys, x0] = ident (dat, order, "s", horizon, "alg", alg);
  catch err
    ## A failure is a result too: the table reports it with SLICOT's message.
    r = getrusage ();
    printf ("RESULT tag=%s status=failed fit_time_s=%.6f maxrss_mb=%.1f base_rss_mb=%.1f reason=%s\n", ...
            tag, toc (t0), r.maxrss / 1024, r0.maxrss / 1024, strrep (err.message, "\n", " "));
    exit (3);
  end_try_catch
  best = min (best, toc (t0));
endfor

[A, B, C, D] = ssdata (sys);
fid = fopen (out, "w");
fprintf (fid, "{\n  \"type\": \"state-space\",\n  \"Ts\": %.17g,\n", Ts);
fprintf (fid, "  \"A\": %s,\n  \"B\": %s,\n  \"C\": %s,\n  \"D\": %s,\n", ...
         json_matrix (A), json_matrix (B), json_matrix (C), json_matrix (D));
fprintf (fid, "  \"provenance\": {\"method\": \"octave-control %s alg %s (SLICOT IB01AD/BD/CD)\", \"order\": %d, \"horizon\": %d}\n}\n", ...
         method, alg, order, horizon);
fclose (fid);

r = getrusage ();
printf ("RESULT tag=%s status=ok fit_time_s=%.6f repeats=%d maxrss_mb=%.1f base_rss_mb=%.1f\n", ...
        tag, best, repeats, r.maxrss / 1024, r0.maxrss / 1024);
