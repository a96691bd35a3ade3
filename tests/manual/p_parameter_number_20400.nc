; TF5200 diagnosis, ID 20400 "P parameter number is 0, negative or greater than maximum limit.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251524747.html
; adapted: the page's ":" line dropped.
; expect: error 20400
N10 G00 X0 Y0 Z0
N20 P0=10
N1000 M30
