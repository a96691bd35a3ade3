; TF5200 diagnosis, ID 21316 "Tangential selection or deselection during active inner corner selection not allowed.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/254188171.html
; adapted: the page's ":" lines dropped.
; expect: end X=100
N10 G238
N100 G41
N110 G01 X100 F1000
N1000 M30
