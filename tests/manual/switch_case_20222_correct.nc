; TF5200 diagnosis, ID 20222 "After 'CASE' only the condition is permissible.": the correct program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/251159179.html
; adapted: the page's ":" lines dropped.
; expect: end X=100 Y=0 Z=0
; expect: runs N45 1
N10   G00 X0 Y0 Z0
N20   P1=5
N30   $SWITCH P1
N40     $CASE 5
N45     G01 X100 F100
N50     $BREAK
N90   $ENDSWITCH
N1000 M30
