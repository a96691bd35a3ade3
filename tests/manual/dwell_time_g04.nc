; TF5200 programming manual, "Dwell time (G04), (#TIME)": G04 example
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206132747.html
; adapted: M30 appended; V.L.TIME declared in #VAR (the page assigns it without a declaration).
; expect: dwell N10 4.5 s
; expect: dwell N20 3.0 s
; expect: dwell N40 2.0 s
; expect: dwell N60 3.5 s
; expect: dwell N80 3.0 s
#VAR
V.L.TIME
#ENDVAR
N10 G04 X4.5          (wait 4.5 seconds)
N20 G04 3.0          (wait 3.0 seconds)
N30 P1=2
N40 G04 P1          (wait 2.0 seconds)
N50 V.L.TIME=3.5
N60 G04 V.L.TIME      (wait 3.5 seconds)
N70 M3 S200
N80 G04 S10          (wait 10 revolutions (wait 3 seconds))
N90 M30
