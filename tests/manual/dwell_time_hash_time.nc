; TF5200 programming manual, "Dwell time (G04), (#TIME)": #TIME example
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206132747.html
; adapted: M30 appended; V.L.TIME declared in #VAR.
; expect: dwell N10 2.5 s
; expect: dwell N30 2.0 s
; expect: dwell N50 3.5 s
#VAR
V.L.TIME
#ENDVAR
N10 #TIME 2.5          (wait 2.5 seconds)
N20 P1=2
N30 #TIME P1          (wait 2.0 seconds)
N40 V.L.TIME=3.5
N50 #TIME V.L.TIME      (wait 3.5 seconds)
N60 M30
